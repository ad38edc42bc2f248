"""tools/bench_table.py (the table of docs/performance.md) on a small fixture of cullide_bench's
JSON output (tests/data/bench_table/cullide_bench.json). Standard library and pytest only: runs
without the cullide module. `python3 -m pytest python/tests/test_bench_table.py`
"""

import importlib.util
import os
import shutil

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
FIXTURE = os.path.join(ROOT, "tests", "data", "bench_table", "cullide_bench.json")
BASELINE = os.path.join(ROOT, "bench", "baseline.json")

spec = importlib.util.spec_from_file_location("bench_table", os.path.join(ROOT, "tools", "bench_table.py"))
bench_table = importlib.util.module_from_spec(spec)
spec.loader.exec_module(bench_table)


def run(tmp_path, *args):
    import contextlib
    import io
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        status = bench_table.main([FIXTURE, "--baseline", BASELINE, *args])
    return status, buf.getvalue()


# Trap: a table without its provenance (which machine, which build) cannot be compared with another.
def test_provenance_names_machine_and_build(tmp_path):
    status, text = run(tmp_path)
    assert status == 0
    first = text.splitlines()[0]
    for word in ("2026-11-28", "fixture-host", "Fixture CPU 9000", "2 CPUs", "2400 MHz",
                 "0123456789abcdef0123456789abcdef01234567", "GCC 12.2.0", "0.3.0", "load average 1.5"):
        assert word in first, word


# Trap: with repetitions, a mean (or the last repetition) reported instead of the median; a name
# with Google Benchmark's "/iterations:40" suffix not recognised as the row's.
def test_repetitions_use_the_median(tmp_path):
    _, text = run(tmp_path)
    line = [l for l in text.splitlines() if "mesh:3" in l][0]
    assert "5.00x" in line and "4.10 ms" in line and "20.5 ms CGAL" in line
    assert "99" not in line


# Trap: ratios not measured in the same run shown as if they were; same-run peers shown wrong.
def test_ratios_and_peers(tmp_path):
    _, text = run(tmp_path)
    lines = text.splitlines()
    hier = [l for l in lines if "BM_Hierarchy" in l][0]
    assert "50.0 ms" in hier and "200 ms 0.1.0 build" in hier and "4.00x" in hier
    tri = [l for l in lines if "direct:1" in l][0]
    assert "40.0 M tris/s" in tri and "10.0 M tris/s tiles" in tri and "4.00x" in tri
    gl = [l for l in lines if "BM_CpuVsGl_Prune" in l][0]
    assert "100 ms" in gl and "1,500 ms llvmpipe" in gl and "15.0x" in gl
    prune = [l for l in lines if "BM_Prune" in l][0]
    assert "300 ms" in prune and "1,011 ms 0.1.0 build (recorded)" in prune and "3.37x (recorded)" in prune


# Trap: a row of the table silently missing when its benchmark was filtered out.
def test_missing_rows_are_named(tmp_path):
    _, text = run(tmp_path)
    assert "Not in this run: `BM_OracleInterleaved/mesh:7/workspace:0/threads:1`." in text


# Trap: --write clobbering the document around the table, or leaving the old table in place.
def test_write_between_markers(tmp_path):
    doc = tmp_path / "perf.md"
    doc.write_text(f"# Before\n\n{bench_table.BEGIN}\nold table\n{bench_table.END}\n\nAfter.\n")
    status, _ = run(tmp_path, "--write", str(doc))
    assert status == 0
    text = doc.read_text()
    assert text.startswith("# Before\n\n" + bench_table.BEGIN + "\nRun of 2026-11-28")
    assert "old table" not in text and text.endswith(bench_table.END + "\n\nAfter.\n")


# Trap: the filter missing the tiles row that x_tiles needs, or a row of the table.
def test_filter_selects_every_row():
    import re
    f = re.compile(bench_table.filter_regex())
    for _, name, _ in bench_table.ROWS:
        assert f.match(name) and f.match(name + "/real_time") and f.match(name + "/iterations:40/real_time")
    assert f.match("BM_Triangles/leg:1/W:500/threads:1/direct:0/real_time")
    assert not f.match("BM_Hierarchy/kind:0/tris:1000000/real_time")
