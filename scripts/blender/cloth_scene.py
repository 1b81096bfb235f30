# Runs one cloth scene in Blender's own cloth solver, headless, and writes what it measured as JSON.
# Called by scripts/compare_blender.py, inside Blender:
#   blender -b --factory-startup -noaudio [-t THREADS] --python-exit-code 1 \
#       -P scripts/blender/cloth_scene.py -- SCENE.json RESULT.json
# SCENE.json (written by compare_blender.py) holds the sheet's grid in sketchdrape's frame
# (metres, +Y up), the pinned vertex indices, the frame count and rate, ClothSettings to change
# from Blender's defaults, and optionally a collision body as vertices and triangles. Blender is Z-up, so a point (x, y, z)
# of sketchdrape is (x, -z, y) here; lengths do not change, so stretch is measured the same way.
import json
import sys
import time

import bpy


def to_blender(p):
    return (p[0], -p[2], p[1])


def from_blender(p):
    return [p[0], p[2], -p[1]]


def add_mesh(name, vertices, faces):
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata([to_blender(v) for v in vertices], [], [tuple(f) for f in faces])
    mesh.update()
    obj = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(obj)
    return obj


def edge_strains(obj, rest_lengths, depsgraph):
    evaluated = obj.evaluated_get(depsgraph)
    mesh = evaluated.to_mesh()
    co = [v.co.copy() for v in mesh.vertices]
    strains = [((co[a] - co[b]).length - r) / r for (a, b), r in rest_lengths]
    positions = [from_blender(c) for c in co]
    evaluated.to_mesh_clear()
    return strains, positions


def main():
    args = sys.argv[sys.argv.index("--") + 1:]
    scene_file, result_file = args[0], args[1]
    with open(scene_file) as f:
        spec = json.load(f)

    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj, do_unlink=True)
    scene = bpy.context.scene
    scene.render.fps = spec["fps"]
    scene.frame_start = 1
    scene.frame_end = spec["frames"] + 1
    scene.gravity = (0.0, 0.0, -9.81)

    sheet = add_mesh("sheet", spec["vertices"], spec["quads"])
    pins = sheet.vertex_groups.new(name="pins")
    pins.add(spec["pinned"], 1.0, "REPLACE")
    cloth = sheet.modifiers.new("cloth", "CLOTH")
    settings = cloth.settings
    settings.quality = spec.get("quality", 5)
    settings.vertex_group_mass = "pins"
    for key, value in spec.get("blender_settings", {}).items():
        setattr(settings, key, value)
    cloth.collision_settings.use_self_collision = spec.get("self_collision", False)
    cloth.point_cache.frame_start = 1
    cloth.point_cache.frame_end = spec["frames"] + 1

    if spec.get("body_vertices"):
        body = add_mesh("body", spec["body_vertices"], spec["body_faces"])
        body.modifiers.new("collision", "COLLISION")

    rest = [v.co.copy() for v in sheet.data.vertices]
    edges = [(e.vertices[0], e.vertices[1]) for e in sheet.data.edges]
    rest_lengths = [((a, b), (rest[a] - rest[b]).length) for a, b in edges]

    # The simulation happens as frames are evaluated in order; time that alone.
    scene.frame_set(1)
    start, start_cpu = time.perf_counter(), time.process_time()
    for frame in range(2, spec["frames"] + 2):
        scene.frame_set(frame)
    seconds, cpu_seconds = time.perf_counter() - start, time.process_time() - start_cpu

    depsgraph = bpy.context.evaluated_depsgraph_get()
    strains, positions = edge_strains(sheet, rest_lengths, depsgraph)
    result = {
        "program": "blender " + bpy.app.version_string,
        "threads": bpy.app.threads if hasattr(bpy.app, "threads") else None,
        "seconds": seconds,
        "cpu_seconds": cpu_seconds,
        "frames": spec["frames"],
        "vertices": len(rest),
        "stretch_max_final": max(strains),
        "positions": positions,
    }
    with open(result_file, "w") as f:
        json.dump(result, f)


main()
