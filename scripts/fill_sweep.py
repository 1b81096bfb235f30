#!/usr/bin/env python3
"""Fill consistency of sketch files over a sweep of edge lengths (docs/garment.md, "Fill
consistency").

For every file and edge length: the file with the panels' and curves' own edge lengths removed
and `edge_length` set (as tests/garment/fill_consistency_test.cpp does), meshed by
`sketchdrape mesh`; from report.json and garment.obj, per panel: quads, partition, distortion,
folded quads, smallest corner, worst aspect ratio, and the quads whose mean side lies outside
0.5-2 edge lengths (small / large, and whether they touch an interior vertex of valence 5 or
more) and those with a side outside it (short_side / long_side); per garment the gate's
warnings. Prints one JSON object per line (file, edge, panel ...) to stdout, or with --summary
the totals (--from-jsonl FILE summarises an earlier output).

    scripts/fill_sweep.py --binary build/sketchdrape --edges 0.02,0.025,0.03,0.035 \
        data/examples/*.json data/designs/*.json > sweep.jsonl
"""
import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
from sketch_json import strip_comments  # scripts/sketch_json.py, beside this file


def read_obj(path):
    vertices, faces, groups, group = [], [], [], None
    with open(path) as f:
        for line in f:
            if line.startswith("v "):
                vertices.append(tuple(float(x) for x in line.split()[1:4]))
            elif line.startswith("g "):
                group = line.split()[1]
            elif line.startswith("f "):
                faces.append([int(x.split("/")[0]) - 1 for x in line.split()[1:]])
                groups.append(group)
    return vertices, faces, groups


def dist(a, b):
    return math.sqrt(sum((x - y) ** 2 for x, y in zip(a, b)))


def band(vertices, faces, groups, edge):
    """Per panel: (small, large, large at interior valence 5+, small at interior valence 3,
    quads with a side under 0.5 e, quads with a side over 2 e)."""
    by_panel = {}
    for f, g in zip(faces, groups):
        by_panel.setdefault(g, []).append(f)
    result = {}
    for panel, quads in by_panel.items():
        uses = {}
        for q in quads:
            for k in range(len(q)):
                e = tuple(sorted((q[k], q[(k + 1) % len(q)])))
                uses[e] = uses.get(e, 0) + 1
        valence, boundary = {}, set()
        for (a, b), count in uses.items():
            for v in (a, b):
                valence[v] = valence.get(v, 0) + 1
                if count == 1:
                    boundary.add(v)
        small = large = large5 = small3 = short_side = long_side = 0
        for q in quads:
            sides = [dist(vertices[q[k]], vertices[q[(k + 1) % 4]]) / edge for k in range(4)]
            short_side += min(sides) < 0.5
            long_side += max(sides) > 2.0
            side = sum(sides) / 4
            if 0.5 <= side <= 2.0:
                continue
            interior = [v for v in q if v not in boundary]
            if side < 0.5:
                small += 1
                small3 += any(valence[v] == 3 for v in interior)
            else:
                large += 1
                large5 += any(valence[v] >= 5 for v in interior)
        result[panel] = (small, large, large5, small3, short_side, long_side)
    return result


def run(binary, path, edge, work):
    with open(path) as f:
        sketch = json.loads(strip_comments(f.read()))
    sketch["edge_length"] = edge
    for panel in sketch.get("panels", []):
        panel.pop("edge_length", None)
    for curve in sketch.get("curves", []):
        curve.pop("edge_length", None)
    sketch["output"] = {"images": []}
    name = os.path.splitext(os.path.basename(path))[0]
    staged = os.path.join(work, f"{name}.json")
    with open(staged, "w") as f:
        json.dump(sketch, f)
    out = os.path.join(work, "out")
    env = dict(os.environ, OMP_THREAD_LIMIT="1", OPENBLAS_NUM_THREADS="1")
    done = subprocess.run([binary, "-q", "mesh", staged, "-o", out], capture_output=True,
                          text=True, env=env)
    if done.returncode != 0:
        return [{"file": name, "edge": edge, "error": done.stderr.strip()[-300:]}]
    with open(os.path.join(out, "report.json")) as f:
        report = json.load(f)
    vertices, faces, groups = read_obj(os.path.join(out, "garment.obj"))
    bands = band(vertices, faces, groups, edge)
    warnings = {}
    for w in report["warnings"]:
        warnings[w["kind"]] = warnings.get(w["kind"], 0) + 1
    rows = []
    for p in report["panels"]:
        q = p["quality"]
        small, large, large5, small3, short_side, long_side = bands.get(p["id"], (0,) * 6)
        rows.append({"file": name, "edge": edge, "panel": p["id"], "mirror": p["mirror_copy"],
                     "quads": p["quads"], "sides": p["side_counts"], "partition": p["partition"],
                     "distortion": p["distortion"], "folded": q["inverted_quads"],
                     "min_angle": q["min_angle_deg"], "max_aspect": q["max_aspect_ratio"],
                     "small": small, "large": large, "large5": large5, "small3": small3,
                     "short_side": short_side, "long_side": long_side})
    rows.append({"file": name, "edge": edge, "panel": None, "warnings": warnings,
                 "quads": len(faces)})
    return rows


def summary(rows):
    """The sweep's totals: quads, quads outside the band, gate warnings (and garments warned),
    folded quads, smallest corner, worst aspect ratio, and panels whose quad count rises as the
    edge length grows (mirror copies left out, as the test does)."""
    garments = [r for r in rows if r.get("panel") is None and "error" not in r]
    panels = [r for r in rows if r.get("panel") is not None and not r["mirror"]]
    counts = {}
    for r in panels:
        counts.setdefault((r["file"], r["panel"]), []).append((r["edge"], r["quads"]))
    rising = sum(any(b[1] > a[1] for a, b in zip(c, c[1:]))
                 for c in (sorted(v) for v in counts.values()))
    every = [r for r in rows if r.get("panel") is not None]
    figures = [
        ("meshes", len(garments)),
        ("refused", sum("error" in r for r in rows)),
        ("quads", sum(r["quads"] for r in garments)),
        ("outside 0.5-2 e (small / large)", "%d (%d / %d)" % (
            sum(r["small"] + r["large"] for r in every), sum(r["small"] for r in every),
            sum(r["large"] for r in every))),
        ("a side outside 0.5-2 e (short / long)", "%d / %d" % (
            sum(r.get("short_side", 0) for r in every), sum(r.get("long_side", 0) for r in every))),
        ("gate warnings (garments warned)", "%d (%d)" % (
            sum(sum(r["warnings"].values()) for r in garments),
            sum(bool(r["warnings"]) for r in garments))),
        ("folded quads", sum(r["folded"] for r in every)),
        ("smallest corner (deg)", "%.2f" % min(r["min_angle"] for r in every)),
        ("worst aspect ratio", "%.1f" % max(r["max_aspect"] for r in every)),
        ("panels not monotone", rising),
    ]
    for name, value in figures:
        print(f"{name:34s} {value}")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--binary", default="build/sketchdrape")
    parser.add_argument("--edges", default="0.02,0.025,0.03,0.035")
    parser.add_argument("--summary", action="store_true",
                        help="print the sweep's totals instead of one JSON object per line")
    parser.add_argument("--from-jsonl", metavar="FILE",
                        help="summarise an earlier sweep's output instead of meshing")
    parser.add_argument("files", nargs="*")
    args = parser.parse_args()
    if args.from_jsonl:
        with open(args.from_jsonl) as f:
            summary([json.loads(line) for line in f if line.strip()])
        return
    if not args.files:
        parser.error("no sketch files given")
    edges = [float(e) for e in args.edges.split(",")]
    rows = []
    with tempfile.TemporaryDirectory() as work:
        for path in args.files:
            for edge in edges:
                for row in run(args.binary, path, edge, work):
                    if args.summary:
                        rows.append(row)
                    else:
                        print(json.dumps(row), flush=True)
    if args.summary:
        summary(rows)


if __name__ == "__main__":
    main()
