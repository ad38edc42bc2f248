"""The per-frame chart of an animated scene: what the oracle sees in each frame (intersecting pairs,
crossing and touching, and near contacts) beside the PCS each image-space method keeps, so that a
reader sees how far a frame's PCS is from its true contacts as the scene moves. (Every method's
time per frame: method_charts.frame_times_chart.)"""
from collections import defaultdict

from .encodings import grid, method_color, ordered, scene_name
from .load import num
from .output import plt, save

# A scene needs this many frames for a line to say more than its points.
MIN_FRAMES = 3


def _by_scene(rows):
    """{scene: {method: {frame: pcs}}} and {scene: {frame: row}} for file scenes run on every frame
    (one configuration per method: the first row of each)."""
    pcs, truth = defaultdict(lambda: defaultdict(dict)), defaultdict(dict)
    for r in rows:
        scene, frame = str(r["scene"]), num(r.get("frame"))
        if "@" in scene or frame is None:
            continue
        truth[scene].setdefault(int(frame), r)
        if r.get("family", "image-space") in ("image-space", "") and num(r.get("pcs")) is not None:
            # (the exact method and the peers keep no PCS)
            pcs[scene][str(r["method"])].setdefault(int(frame), num(r["pcs"]))
    return {s: pcs[s] for s in truth if len(truth[s]) >= MIN_FRAMES}, truth


def frames_chart(rows, out):
    """Per frame of each animated scene: the oracle's crossing and touching pairs, its near contacts
    (where counted) and each method's PCS, on a log scale."""
    pcs, truth = _by_scene(rows)
    if not pcs:
        return None
    scenes = list(pcs)
    cols, nrows = grid(len(scenes))
    fig, axes = plt.subplots(nrows, cols, figsize=(6.4 * cols, 4.2 * nrows), squeeze=False)
    methods = ordered(str(r["method"]) for r in rows)
    for ax, scene in zip(axes.flat, scenes):
        frames = sorted(truth[scene])
        series = [("crossing pairs", "oracle_crossing", "k", "-"), ("touching pairs", "oracle_touching", "k", ":"),
                  ("near contacts", "near_contacts", "tab:gray", "--"),
                  ("near contacts within objects", "near_contacts_self", "tab:gray", ":")]
        for label, column, color, style in series:
            ys = [num(truth[scene][f].get(column)) for f in frames]
            if all(y is not None for y in ys):
                ax.plot(frames, ys, color=color, linestyle=style, linewidth=1.4, label=label)
        for m in methods:
            if m in pcs[scene]:
                ys = [pcs[scene][m].get(f) for f in frames]
                ax.plot(frames, ys, color=method_color(m, methods), linewidth=1.6, label=f"PCS, {m}")
        ax.set_yscale("symlog", linthresh=10)
        ax.set_xlabel("frame")
        ax.set_ylabel("pairs / triangles")
        ax.set_title(scene_name(scene) + f" ({int(num(truth[scene][frames[0]]['triangles']))} triangles)")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    for ax in list(axes.flat)[len(scenes):]:
        ax.set_visible(False)
    fig.tight_layout()
    save(fig, out, "frames")
    return "frames"
