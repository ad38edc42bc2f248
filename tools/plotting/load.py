"""Reading the inputs: text (UTF-8), CSV rows and JSON lines with the line each came from, JSON
files, numbers. Input that cannot be read raises InputError, which the command line reports as
`cullide: error: PATH: CAUSE` with exit status 2 (cli.main)."""
import csv
import io
import json
import os
import sys

MAX_BYTES = 4 << 30  # as cullide's own readers: a larger file is no output of cullide's


class InputError(Exception):
    """An input (or output) that cannot be used, and why: the message is `PATH: CAUSE`."""

    def __init__(self, path, cause):
        super().__init__(f"{path}: {cause}")


class Row(dict):
    """A CSV row (column: cell text) or a JSON line's object, with its line number for messages."""

    line = 0


def num(v):
    try:
        return float(v)
    except (TypeError, ValueError):
        return None


def warn(path, text):
    print(f"cullide: warning: {path}: {text}", file=sys.stderr)


def read_text(path):
    """The file's text. Only regular files are read (a FIFO would block, a device never end),
    up to MAX_BYTES; a UTF-8 byte-order mark is dropped; anything but UTF-8 text is refused."""
    if not os.path.isfile(path):
        raise InputError(path, "not a regular file" if os.path.exists(path) else "no such file")
    size = os.path.getsize(path)
    if size > MAX_BYTES:
        raise InputError(path, f"{size} bytes, over the limit of {MAX_BYTES} bytes")
    with open(path, "rb") as f:
        data = f.read()
    if data[:2] in (b"\xff\xfe", b"\xfe\xff"):
        raise InputError(path, "UTF-16 text: cullide reads UTF-8")
    nul = data.find(b"\0")
    if nul >= 0:
        raise InputError(path, f"binary data (a NUL byte at byte {nul}), not text")
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as e:
        line = data.count(b"\n", 0, e.start) + 1
        raise InputError(path, f"not UTF-8 text (line {line}, byte {e.start})") from None


def cut_last_line(text):
    """Whether the text's last line has no end of line: cullide ends every line it writes, so such
    a line was cut (by a killed run)."""
    return bool(text) and not text.endswith("\n")


def read_csv(path):
    """(header, rows): the header's column names and a Row per line. A row with more or fewer
    cells than the header is refused with its line, except a cut last line, which is skipped
    with a warning (as `cullide study` does when it resumes)."""
    text = read_text(path)
    reader = csv.reader(io.StringIO(text, newline=""), strict=True)
    lines = []
    try:
        for cells in reader:
            if cells:  # a blank line is no row
                lines.append((reader.line_num, cells))
    except csv.Error as e:
        raise InputError(path, f"line {reader.line_num}: malformed CSV ({e})") from None
    if not lines:
        raise InputError(path, "empty: no header line")
    (_, header), rows = lines[0], lines[1:]
    twice = sorted({c for c in header if header.count(c) > 1})
    if twice:
        raise InputError(path, f"line 1: the header names {', '.join(twice)} twice")
    if rows and cut_last_line(text):
        warn(path, f"line {rows[-1][0]} is cut (no end of line: a killed run's), skipped")
        rows.pop()
    out = []
    for line, cells in rows:
        if len(cells) != len(header):
            raise InputError(path, f"line {line} has {len(cells)} cell{'s' if len(cells) != 1 else ''} where the "
                                   f"header (line 1) has {len(header)}")
        r = Row(zip(header, cells))
        r.line = line
        out.append(r)
    return header, out


def csv_header(path):
    """The column names on a CSV file's first line (what kind of file it is)."""
    text = read_text(path)
    try:
        header = next(csv.reader(io.StringIO(text, newline=""), strict=True), None)
    except csv.Error as e:
        raise InputError(path, f"line 1: malformed CSV ({e})") from None
    if not header:
        raise InputError(path, "empty: no header line")
    return header


def json_error(e):
    if isinstance(e, json.JSONDecodeError):
        return f"not JSON ({e.msg}: line {e.lineno}, column {e.colno})"
    if isinstance(e, RecursionError):
        return "not JSON that cullide reads (nested too deeply)"
    return f"not JSON ({e})"


def read_jsonl(path):
    """A Row per JSON line (blank lines skipped). A line that is not a JSON object is refused with
    its number, except a cut last line, which is skipped with a warning."""
    text = read_text(path)
    lines = text.split("\n")
    out = []
    for i, s in enumerate(lines, 1):
        if not s.strip():
            continue
        try:
            j = json.loads(s)
        except (ValueError, RecursionError) as e:
            if i == len(lines) and cut_last_line(text):
                warn(path, f"line {i} is cut (no end of line: a killed run's), skipped")
                break
            raise InputError(path, f"line {i}: {json_error(e)}") from None
        if not isinstance(j, dict):
            raise InputError(path, f"line {i}: a JSON {type(j).__name__}, not a record (a JSON object)")
        r = Row(j)
        r.line = i
        out.append(r)
    return out


def read_json(path):
    try:
        return json.loads(read_text(path))
    except (ValueError, RecursionError) as e:
        raise InputError(path, json_error(e)) from None
