#!/usr/bin/env python3
"""Side by side: the same cloth scenes in sketchdrape and in Blender's cloth solver.

Each scene is a 1 m square of cotton (mass from data/fabrics/cotton.json), horizontal, simulated
for FRAMES frames at FPS (default 48 at 24 fps, 2 s), either pinned at its two far corners
("pinned") or dropped from 10 cm onto a sphere of radius 0.3 m ("sphere"), at N x N quads.
Both programs get the same grid, pins and (for the sphere) the same triangle mesh; each runs
with its own default settings unless told otherwise (--blender-set, --sketchdrape-set). Blender's
defaults are its cotton-like material (vertex mass 0.3 kg, tension 15, bending 0.5, air 1):
its stiffness, damping and air drag are absolute forces, not per unit mass, so they only make
sense with its default vertex mass. Giving it cotton's real mass instead (0.13 kg/m^2, about half
a gram a vertex; --blender-mass matched) leaves the sheet overdamped: measured, the centre of
mass of the pinned 16 x 16 sheet fell 8 mm in 1 s (70 mm without air) where sketchdrape's fell
0.47 m. The table reports how far each sheet's centre of mass fell, to show the two simulated
comparable motions.

Measured for each: the simulation's wall time (Blender: the frame evaluations; sketchdrape: the
report's wall_time_s, the simulator's run without loading and output) and CPU time, like with
like (Blender: the frame evaluations, all threads; sketchdrape: the report's cpu_time_s, the
stepping on all threads, without loading and output; the whole process's CPU time, loading and
writing included, is given as well),
and the final stretch: the largest relative elongation of the sheet's grid edges (warp and
weft; diagonals are shear, not stretch), computed the same way from both programs' final
positions. Writes results.json and results.md (a Markdown table) to --out.

    scripts/compare_blender.py --sizes 32 64 --scenes pinned sphere -o out/blender
    scripts/compare_blender.py --blender-threads 0   # Blender on every core (its default)
    scripts/compare_blender.py --scenes ball --sizes 32 --self-collision   # a folding scene
    scripts/compare_blender.py --cases pinned:128 --pin-radius 0.02   # 2 cm corner clamps in both

Needs Debian's blender (apt-get install blender) and a built sketchdrape. Timings mean
something only on a quiet machine: the table states the load average before and after.
"""
import argparse
import json
import math
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SPHERE_RADIUS = 0.3
BALL_RADIUS = 0.1  # the folding scene ("ball"): a 1 m sheet hangs around a 10 cm ball
PINNED_HEIGHT = 1.2
DROP = 0.1  # metres between the sphere's top and the sheet


def grid(n, height):
    """(n+1)^2 vertices of the horizontal 1 m sheet, row by row from the far edge (-z)."""
    vertices = []
    for row in range(n + 1):
        z = -0.5 + row / n
        for col in range(n + 1):
            vertices.append([-0.5 + col / n, height, z])
    quads = []
    for row in range(n):
        for col in range(n):
            a = row * (n + 1) + col
            quads.append([a, a + 1, a + n + 2, a + n + 1])
    return vertices, quads


def icosphere(radius, centre, subdivisions):
    t = (1 + math.sqrt(5)) / 2
    v = [[-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0], [0, -1, t], [0, 1, t], [0, -1, -t],
         [0, 1, -t], [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1]]
    f = [[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4],
         [11, 10, 2], [10, 7, 6], [7, 1, 8], [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8],
         [3, 8, 9], [4, 9, 5], [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1]]
    v = [[c / math.sqrt(sum(x * x for x in p)) for c in p] for p in v]
    for _ in range(subdivisions):
        cache = {}

        def mid(a, b):
            key = (min(a, b), max(a, b))
            if key not in cache:
                m = [(v[a][i] + v[b][i]) / 2 for i in range(3)]
                norm = math.sqrt(sum(x * x for x in m))
                v.append([x / norm for x in m])
                cache[key] = len(v) - 1
            return cache[key]

        nf = []
        for a, b, c in f:
            ab, bc, ca = mid(a, b), mid(b, c), mid(c, a)
            nf += [[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]
        f = nf
    return [[centre[i] + radius * p[i] for i in range(3)] for p in v], f


def grid_edges(quads):
    edges = set()
    for q in quads:
        for k in range(4):
            a, b = q[k], q[(k + 1) % 4]
            edges.add((min(a, b), max(a, b)))
    return sorted(edges)


def stretch_max(rest, final, edges):
    def length(p, a, b):
        return math.dist(p[a], p[b])

    return max((length(final, a, b) - length(rest, a, b)) / length(rest, a, b) for a, b in edges)


# A pin is one vertex in both programs, and a point load on a membrane has a strain that grows
# as 1/r towards it (on a mesh, as 1/h at the pinned vertex), so the largest stretch of a pinned
# sheet measures the mesh at the pin more than the solver (docs/benchmarks.md, "Sixth round").
# The table also gives the largest stretch of the edges farther than this from every pin (m):
# the size of a clip or of fingers holding a corner.
PIN_CLEARANCE = 0.02


def edges_away_from_pins(rest, edges, pinned, radius):
    def far(a, b):
        middle = [(rest[a][k] + rest[b][k]) / 2 for k in range(3)]
        return all(math.dist(middle, rest[p]) > radius for p in pinned)

    return [(a, b) for a, b in edges if far(a, b)]


def count_intersections(positions, triangles):
    """Pairs of triangles not sharing an edge that intersect: an edge of one (not through a
    shared vertex) crosses the other (orientation signs, rounding-level values as zero; a uniform
    grid of cells the size of the largest triangle finds the candidates)."""
    def sub(a, b):
        return (a[0] - b[0], a[1] - b[1], a[2] - b[2])

    def orient(a, b, c, d):
        u, v, w = sub(b, a), sub(c, a), sub(d, a)
        return (u[1] * v[2] - u[2] * v[1]) * w[0] + (u[2] * v[0] - u[0] * v[2]) * w[1] + \
            (u[0] * v[1] - u[1] * v[0]) * w[2]

    def crosses(p, q, a, b, c):
        eps = 1e-10 * max(math.dist(p, q), math.dist(a, b), math.dist(a, c)) ** 3
        d1, d2 = orient(a, b, c, p), orient(a, b, c, q)
        if (d1 > eps and d2 > eps) or (d1 < -eps and d2 < -eps) or (abs(d1) <= eps and abs(d2) <= eps):
            return False
        e = (orient(p, q, a, b), orient(p, q, b, c), orient(p, q, c, a))
        return all(x >= -eps for x in e) or all(x <= eps for x in e)

    boxes = [(tuple(min(positions[k][a] for k in t) for a in range(3)),
              tuple(max(positions[k][a] for k in t) for a in range(3))) for t in triangles]
    cell = max(max(hi[a] - lo[a] for a in range(3)) for lo, hi in boxes) + 1e-12
    grid = {}
    for i, (lo, hi) in enumerate(boxes):
        ranges = [range(math.floor(lo[a] / cell), math.floor(hi[a] / cell) + 1) for a in range(3)]
        for x in ranges[0]:
            for y in ranges[1]:
                for z in ranges[2]:
                    grid.setdefault((x, y, z), []).append(i)
    found = set()
    for members in grid.values():
        for m, i in enumerate(members):
            for j in members[m + 1:]:
                key = (min(i, j), max(i, j))
                if key in found:
                    continue
                (li, hi_), (lj, hj) = boxes[i], boxes[j]
                if any(hi_[a] < lj[a] or hj[a] < li[a] for a in range(3)):
                    continue
                ti, tj = triangles[i], triangles[j]
                if len(set(ti) & set(tj)) >= 2:
                    continue
                for t, u in ((ti, tj), (tj, ti)):
                    if any(crosses(positions[t[k]], positions[t[(k + 1) % 3]], positions[u[0]],
                                   positions[u[1]], positions[u[2]])
                           for k in range(3) if t[k] not in u and t[(k + 1) % 3] not in u):
                        found.add(key)
                        break
    return len(found)


def read_obj_triangles(path):
    with open(path) as f:
        return [tuple(int(x.split("/")[0]) - 1 for x in line.split()[1:4])
                for line in f if line.startswith("f ")]


def read_obj_vertices(path):
    with open(path) as f:
        return [[float(x) for x in line.split()[1:4]] for line in f if line.startswith("v ")]


def reorder_to_grid(obj_vertices_rest, grid_vertices):
    """Index map grid vertex -> OBJ vertex, by position (the OBJ of a run stopped after one
    0.1 ms step, so every vertex is within micrometres of its grid point)."""
    key = {}
    for i, p in enumerate(obj_vertices_rest):
        key[(round(p[0], 4), round(p[2], 4))] = i
    mapping = []
    for p in grid_vertices:
        k = (round(p[0], 4), round(p[2], 4))
        if k not in key:
            raise RuntimeError(f"sketchdrape's sheet has no vertex at grid point {p}")
        mapping.append(key[k])
    return mapping


def run_sketchdrape(binary, scene, workdir, extra):
    scene_file = workdir / "scene.json"
    scene_file.write_text(json.dumps(scene, indent=1))
    out = workdir / "sketchdrape"
    command = [str(binary), "run", str(scene_file), "-o", str(out)] + extra
    start, before = time.perf_counter(), resource.getrusage(resource.RUSAGE_CHILDREN)
    done = subprocess.run(command, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    if done.returncode != 0:
        sys.exit(f"sketchdrape failed ({done.returncode}) on {scene_file}:\n{done.stderr}")
    wall, after = time.perf_counter() - start, resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime + after.ru_stime) - (before.ru_utime + before.ru_stime)
    report = json.loads((out / "report.json").read_text())
    return report, wall, cpu, read_obj_vertices(out / "drape.obj")


def run_blender(blender, threads, spec, workdir):
    spec_file, result_file = workdir / "blender-scene.json", workdir / "blender-result.json"
    spec_file.write_text(json.dumps(spec))
    command = [blender, "-b", "--factory-startup", "-noaudio", "--python-exit-code", "1"]
    if threads is not None:
        command += ["-t", str(threads)]
    command += ["-P", str(ROOT / "scripts/blender/cloth_scene.py"), "--", str(spec_file),
                str(result_file)]
    start = time.perf_counter()
    done = subprocess.run(command, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    wall = time.perf_counter() - start
    if done.returncode != 0:
        sys.exit(f"blender failed ({done.returncode}) on {spec_file}:\n{done.stderr[-2000:]}")
    return json.loads(result_file.read_text()), wall


def parse_settings(pairs):
    settings = {}
    for pair in pairs:
        key, _, value = pair.partition("=")
        try:
            settings[key] = json.loads(value)
        except json.JSONDecodeError:
            settings[key] = value
    return settings


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--binary", default=str(ROOT / "build/sketchdrape"))
    parser.add_argument("--blender", default="blender")
    parser.add_argument("--sizes", type=int, nargs="+", default=[32, 64])
    parser.add_argument("--scenes", nargs="+", default=["pinned", "sphere"],
                        choices=["pinned", "sphere", "ball"])
    parser.add_argument("--cases", nargs="+", default=None, metavar="SCENE:N",
                        help="scenes and sizes to run instead of every --scenes x --sizes pair, "
                        "e.g. pinned:32 pinned:64 pinned:128 sphere:32 sphere:64")
    parser.add_argument("--self-collision", action="store_true",
                        help="self-collision on in both programs; the table adds intersecting "
                             "triangle pairs of each final sheet")
    parser.add_argument("--pin-radius", type=float, default=0.0, metavar="R",
                        help="metres: each pinned corner holds every vertex within R of it, in "
                        "both programs (sketchdrape's \"top-left:R\", the same vertices in "
                        "Blender's pin group); default 0, one vertex a corner")
    parser.add_argument("--frames", type=int, default=48)
    parser.add_argument("--fps", type=int, default=24)
    parser.add_argument("--fabric", default="cotton")
    parser.add_argument("--blender-threads", type=int, default=1,
                        help="Blender's -t (0: every core, its default); default 1")
    parser.add_argument("--blender-mass", choices=["default", "matched"], default="default",
                        help="Blender's vertex mass: its default, or cotton's real mass")
    parser.add_argument("--blender-set", nargs="*", default=[], metavar="KEY=VALUE",
                        help="Blender ClothSettings to change, e.g. tension_stiffness=500")
    parser.add_argument("--sketchdrape-set", nargs="*", default=[], metavar="KEY=VALUE",
                        help="keys of the scene's \"simulate\" object, e.g. time_step=0.0333")
    parser.add_argument("-o", "--out", default=str(ROOT / "out/blender-compare"))
    args = parser.parse_args()

    density = json.loads((ROOT / f"data/fabrics/{args.fabric}.json").read_text())
    density = density["area_density"]["value"]
    out = Path(args.out).resolve()  # the scene files name the sphere by absolute path
    out.mkdir(parents=True, exist_ok=True)
    load_before = os.getloadavg()[0]
    rows = []
    if args.cases:
        cases = [(c.split(":")[0], int(c.split(":")[1])) for c in args.cases]
    else:
        cases = [(scene_name, n) for scene_name in args.scenes for n in args.sizes]
    for scene_name, n in cases:
        radius = BALL_RADIUS if scene_name == "ball" else SPHERE_RADIUS
        height = PINNED_HEIGHT if scene_name == "pinned" else 2 * radius + DROP
        vertices, quads = grid(n, height)
        pinned = [0, n] if scene_name == "pinned" else []
        if pinned and args.pin_radius > 0:
            # A corner clamp: the grid points within R of each corner (1 um tolerance, as
            # sketchdrape's build_sheet), checked below against the count sketchdrape held.
            corners = [vertices[c] for c in pinned]
            pinned = [i for i, p in enumerate(vertices)
                      if any(math.dist(p, c) <= args.pin_radius + 1e-6 for c in corners)]
        pin_names = ["top-left", "top-right"]
        if args.pin_radius > 0:
            pin_names = [f"{name}:{args.pin_radius:g}" for name in pin_names]
        duration = args.frames / args.fps
        simulate = {"duration": duration, "stop_at_rest": False,
                    "self_collision": args.self_collision}
        simulate.update(parse_settings(args.sketchdrape_set))
        scene = {
            "format": "sketchdrape/1",
            "sheet": {"size": [1.0, 1.0], "resolution": [n, n], "orientation": "horizontal",
                      "centre": [0.0, height, 0.0],
                      "pins": pin_names if pinned else []},
            "fabric": args.fabric,
            "simulate": simulate,
            "output": {"images": [], "mesh": "drape.obj"},
        }
        blender_settings = parse_settings(args.blender_set)
        if args.blender_mass == "matched":
            blender_settings["mass"] = density * 1.0 / len(vertices)
        spec = {"vertices": vertices, "quads": quads, "pinned": pinned, "frames": args.frames,
                "fps": args.fps, "blender_settings": blender_settings,
                "self_collision": args.self_collision}
        with tempfile.TemporaryDirectory(dir=out) as tmp:
            workdir = Path(tmp)
            if scene_name in ("sphere", "ball"):
                body_v, body_f = icosphere(radius, [0.0, radius, 0.0], 4)
                with open(workdir / "sphere.obj", "w") as f:
                    f.writelines(f"v {p[0]} {p[1]} {p[2]}\n" for p in body_v)
                    f.writelines(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in body_f)
                scene["body"] = {"mesh": str(workdir / "sphere.obj"), "scale": 1.0}
                spec["body_vertices"], spec["body_faces"] = body_v, body_f
            # The sheet's vertex order in sketchdrape's output: a run of one 0.1 ms step.
            first = json.loads(json.dumps(scene))
            first["simulate"] = {"duration": 1e-4, "time_step": 1e-4, "stop_at_rest": False,
                                 "self_collision": False}
            _, _, _, rest_obj = run_sketchdrape(args.binary, first, workdir, [])
            mapping = reorder_to_grid(rest_obj, vertices)
            report, sd_wall, sd_cpu, final_obj = run_sketchdrape(args.binary, scene, workdir,
                                                                 [])
            sd_final = [final_obj[i] for i in mapping]
            if report["pinned_vertices"] != len(pinned):
                sys.exit(f"sketchdrape held {report['pinned_vertices']} vertices, this script "
                         f"pins {len(pinned)} in Blender: the comparison would not be fair")
            sd_triangles = read_obj_triangles(workdir / "sketchdrape" / "drape.obj")
            blender, b_wall = run_blender(args.blender, args.blender_threads, spec, workdir)
        edges = grid_edges(quads)
        row = {
            "scene": f"{scene_name} {n}x{n}",
            "vertices": len(vertices),
            "blender_s": blender["seconds"],
            "blender_cpu_s": blender["cpu_seconds"],
            "blender_wall_s": b_wall,
            "blender_stretch_max": stretch_max(vertices, blender["positions"], edges),
            "sketchdrape_s": report["wall_time_s"],
            "sketchdrape_process_wall_s": sd_wall,
            "sketchdrape_process_cpu_s": sd_cpu,
            "sketchdrape_cpu_s": report["cpu_time_s"],
            "sketchdrape_stretch_max": stretch_max(vertices, sd_final, edges),
            "sketchdrape_settings": report["settings"],
            "sketchdrape_steps": report["steps"],
            "pinned_vertices": len(pinned),
        }
        if pinned:
            away = edges_away_from_pins(vertices, edges, pinned, PIN_CLEARANCE)
            row["blender_stretch_beyond_pins"] = stretch_max(vertices, blender["positions"], away)
            row["sketchdrape_stretch_beyond_pins"] = stretch_max(vertices, sd_final, away)
        # How far the sheet's centre of mass fell: both programs simulated the same thing.
        row["blender_drop_m"] = height - sum(p[1] for p in blender["positions"]) / len(vertices)
        row["sketchdrape_drop_m"] = height - sum(p[1] for p in sd_final) / len(vertices)
        if args.self_collision:
            # Each final sheet counted by the same test on the triangles its program
            # simulated: Blender's quads split along their first diagonal (as its cloth
            # tessellates a convex quad), sketchdrape's own 4-8 triangles; and sketchdrape's
            # CGAL count of its mesh.
            triangles = [t for a, b, c, d in quads for t in ((a, b, c), (a, c, d))]
            row["blender_intersections"] = count_intersections(blender["positions"], triangles)
            row["sketchdrape_intersections"] = count_intersections(
                final_obj, sd_triangles)
            row["sketchdrape_intersections_cgal"] = report["self_intersections_final"]
            row["sketchdrape_self_collision_share"] = report["self_collision_share"]
        row["speedup"] = row["blender_s"] / row["sketchdrape_s"]
        # Like with like: both programs' simulation alone, every thread.
        row["cpu_speedup"] = row["blender_cpu_s"] / row["sketchdrape_cpu_s"]
        row["process_cpu_speedup"] = row["blender_cpu_s"] / row["sketchdrape_process_cpu_s"]
        rows.append(row)
        print(f"{row['scene']}: Blender {row['blender_s']:.2f} s, stretch "
              f"{100 * row['blender_stretch_max']:.2f} %; sketchdrape "
              f"{row['sketchdrape_s']:.2f} s, stretch "
              f"{100 * row['sketchdrape_stretch_max']:.2f} %; ratio {row['speedup']:.2f}; "
              f"centre of mass fell {row['blender_drop_m']:.3f} / "
              f"{row['sketchdrape_drop_m']:.3f} m",
              flush=True)
    load_after = os.getloadavg()[0]
    blender_version = blender["program"] if rows else "?"
    meta = {"blender": blender_version, "blender_threads": args.blender_threads,
            "frames": args.frames, "fps": args.fps, "fabric": args.fabric,
            "blender_set": args.blender_set, "self_collision": args.self_collision, "blender_mass": args.blender_mass, "sketchdrape_set": args.sketchdrape_set,
            "pin_radius_m": args.pin_radius,
            "load_average_before": load_before, "load_average_after": load_after,
            "cores": os.cpu_count()}
    (out / "results.json").write_text(json.dumps({"meta": meta, "rows": rows}, indent=1))
    lines = [
        f"{blender_version} (threads: {args.blender_threads or 'all'}) against sketchdrape "
        f"({', '.join(args.sketchdrape_set) or 'default settings'}); {args.frames} frames at "
        f"{args.fps} fps, {args.fabric}; "
        + (f"corner clamps of {args.pin_radius:g} m; " if args.pin_radius > 0 else "")
        + f"load average {load_before:.1f} before, "
        f"{load_after:.1f} after, {os.cpu_count()} cores.",
        "",
        "| scene | wall: Blender / sketchdrape (ratio) | CPU: Blender / sketchdrape (ratio) "
        "| sketchdrape's whole process, CPU (ratio) "
        "| stretch max: Blender / sketchdrape "
        f"| beyond {100 * PIN_CLEARANCE:.0f} cm of a pin: Blender / sketchdrape "
        "| centre of mass fell: Blender / sketchdrape |",
        "|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(f"| {r['scene']} | {r['blender_s']:.2f} s / {r['sketchdrape_s']:.2f} s "
                     f"({r['speedup']:.2f}x) | {r['blender_cpu_s']:.2f} s / "
                     f"{r['sketchdrape_cpu_s']:.2f} s ({r['cpu_speedup']:.2f}x) | "
                     f"{r['sketchdrape_process_cpu_s']:.2f} s ({r['process_cpu_speedup']:.2f}x) | "
                     f"{100 * r['blender_stretch_max']:.1f} % / "
                     f"{100 * r['sketchdrape_stretch_max']:.2f} % | "
                     + (f"{100 * r['blender_stretch_beyond_pins']:.1f} % / "
                        f"{100 * r['sketchdrape_stretch_beyond_pins']:.2f} % | "
                        if "blender_stretch_beyond_pins" in r else "– | ")
                     + f"{r['blender_drop_m']:.3f} / "
                     f"{r['sketchdrape_drop_m']:.3f} m |")
    if args.self_collision:
        lines += ["", "| scene | intersecting triangle pairs: Blender / sketchdrape (its CGAL "
                  "count) | sketchdrape's self-collision share |", "|---|---|---|"]
        for r in rows:
            lines.append(f"| {r['scene']} | {r['blender_intersections']} / "
                         f"{r['sketchdrape_intersections']} ({r['sketchdrape_intersections_cgal']}) "
                         f"| {100 * r['sketchdrape_self_collision_share']:.0f} % |")
    (out / "results.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    sys.exit(main())
