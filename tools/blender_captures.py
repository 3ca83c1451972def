"""Photographs a tree file with Blender's Cycles into a NeRF-synthetic capture folder.

The captures volumetric_opacity is measured on should come from trees and a renderer Canopy does
not use for its own reference, so this script renders an OBJ/GLB made by another tool (e.g. the
Sapling add-on or ez-tree) with Cycles. It writes what `{"captures": DIR}` reads:
transforms_train.json and transforms_test.json (camera_angle_x, camera-to-world
transform_matrix looking down -Z, Blender's Z-up world) and RGBA PNGs with a transparent
background, the alpha being the tree's coverage.

  blender -b --factory-startup -P tools/blender_captures.py -- \
      --model ../shared/assets/sapling_small_maple/small_maple_s1.obj --out caps/maple \
      [--train 22] [--test 8] [--resolution 512] [--distance 3] [--samples 32] [--seed 1]

Training cameras lie on a Fibonacci spiral over the sphere above 10 degrees below the horizon;
test cameras on a second spiral turned by half the golden angle, so none coincides with a
training camera. Everything is deterministic in --seed (Cycles' own seed included).
"""

import argparse
import json
import math
import os
import sys

import bpy
from mathutils import Matrix, Vector


def parse_arguments():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--model", required=True, help="OBJ or GLB tree file")
    parser.add_argument("--out", required=True, help="capture folder to write")
    parser.add_argument("--train", type=int, default=22, help="training views")
    parser.add_argument("--test", type=int, default=8, help="held-out test views")
    parser.add_argument("--resolution", type=int, default=512, help="pixels per side")
    parser.add_argument("--distance", type=float, default=3.0,
                        help="camera distance from the tree's centre in bounding radii")
    parser.add_argument("--fov", type=float, default=30.0, help="horizontal field of view, degrees")
    parser.add_argument("--samples", type=int, default=32, help="Cycles samples per pixel")
    parser.add_argument("--seed", type=int, default=1, help="Cycles seed")
    arguments = parser.parse_args(argv)
    if not os.path.isfile(arguments.model):
        sys.exit(f"blender_captures: {arguments.model}: no such file")
    if arguments.train < 2 or arguments.test < 1 or arguments.resolution < 16:
        sys.exit("blender_captures: --train >= 2, --test >= 1 and --resolution >= 16")
    return arguments


def import_model(path):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    if path.lower().endswith((".glb", ".gltf")):
        bpy.ops.import_scene.gltf(filepath=path)
    elif hasattr(bpy.ops.wm, "obj_import"):
        bpy.ops.wm.obj_import(filepath=path)
    else:
        bpy.ops.import_scene.obj(filepath=path)
    meshes = [o for o in bpy.context.scene.objects if o.type == "MESH"]
    if not meshes:
        sys.exit(f"blender_captures: {path}: no mesh imported")
    for material in bpy.data.materials:
        # Leaf cards carry their outline in alpha: cut it out in the path tracer too.
        material.blend_method = "CLIP"
    return meshes


def bounding_sphere(meshes):
    corners = [o.matrix_world @ Vector(c) for o in meshes for c in o.bound_box]
    lo = Vector((min(c.x for c in corners), min(c.y for c in corners), min(c.z for c in corners)))
    hi = Vector((max(c.x for c in corners), max(c.y for c in corners), max(c.z for c in corners)))
    return (lo + hi) * 0.5, (hi - lo).length * 0.5


def spiral_directions(count, turn):
    """Unit directions on a Fibonacci spiral from 10 degrees below the horizon to the zenith."""
    golden = math.pi * (3.0 - math.sqrt(5.0))
    lowest = math.sin(math.radians(-10.0))
    directions = []
    for i in range(count):
        z = lowest + (1.0 - lowest) * (i + 0.5) / count
        ring = math.sqrt(max(0.0, 1.0 - z * z))
        angle = golden * i + turn
        directions.append(Vector((ring * math.cos(angle), ring * math.sin(angle), z)))
    return directions


def set_up_scene(arguments):
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = arguments.samples
    scene.cycles.seed = arguments.seed
    scene.cycles.use_denoising = False  # deterministic, and no denoiser smearing leaf edges
    scene.render.film_transparent = True
    scene.render.resolution_x = scene.render.resolution_y = arguments.resolution
    scene.render.resolution_percentage = 100
    scene.render.image_settings.file_format = "PNG"
    scene.render.image_settings.color_mode = "RGBA"
    scene.view_settings.view_transform = "Standard"  # sRGB, as Canopy reads PNGs
    world = bpy.data.worlds.new("sky")
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.6, 0.65, 0.75, 1.0)
    world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.8
    scene.world = world
    sun = bpy.data.objects.new("sun", bpy.data.lights.new("sun", type="SUN"))
    sun.data.energy = 3.0
    sun.rotation_euler = (math.radians(40.0), 0.0, math.radians(30.0))
    scene.collection.objects.link(sun)
    camera = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
    camera.data.sensor_fit = "HORIZONTAL"
    camera.data.angle = math.radians(arguments.fov)
    scene.collection.objects.link(camera)
    scene.camera = camera
    return scene, camera


def look_at(position, target):
    forward = (target - position).normalized()
    up = Vector((0.0, 0.0, 1.0))
    if abs(forward.dot(up)) > 0.999:
        up = Vector((0.0, 1.0, 0.0))
    right = forward.cross(up).normalized()
    true_up = right.cross(forward)
    rotation = Matrix((right, true_up, -forward)).transposed()  # columns: x, y, z (= backward)
    return Matrix.Translation(position) @ rotation.to_4x4()


def render_split(scene, camera, directions, center, distance, folder, split, fov):
    frames = []
    os.makedirs(os.path.join(folder, split), exist_ok=True)
    for i, direction in enumerate(directions):
        camera.matrix_world = look_at(center + direction * distance, center)
        name = f"{split}/r_{i}"
        scene.render.filepath = os.path.join(folder, name + ".png")
        bpy.ops.render.render(write_still=True)
        frames.append({"file_path": "./" + name,
                       "transform_matrix": [list(row) for row in camera.matrix_world]})
        print(f"blender_captures: {split} {i + 1}/{len(directions)}", flush=True)
    document = {"camera_angle_x": math.radians(fov), "frames": frames}
    temporary = os.path.join(folder, f"transforms_{split}.json.tmp")
    with open(temporary, "w") as out:
        json.dump(document, out, indent=1)
    os.replace(temporary, os.path.join(folder, f"transforms_{split}.json"))


def main():
    arguments = parse_arguments()
    meshes = import_model(arguments.model)
    center, radius = bounding_sphere(meshes)
    scene, camera = set_up_scene(arguments)
    distance = arguments.distance * radius
    camera.data.clip_start = max(1e-3, distance - 2.0 * radius)
    camera.data.clip_end = distance + 2.0 * radius
    golden = math.pi * (3.0 - math.sqrt(5.0))
    render_split(scene, camera, spiral_directions(arguments.train, 0.0), center, distance,
                 arguments.out, "train", arguments.fov)
    render_split(scene, camera, spiral_directions(arguments.test, 0.5 * golden), center,
                 distance, arguments.out, "test", arguments.fov)


main()
