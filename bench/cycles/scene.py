"""The reference's Cycles scene (bench/cycles/sphere.json: the same 96-segment sphere mesh), built and rendered by Blender's Cycles.

Run by bench/cycles/run.sh: blender -b --factory-startup --python scene.py -- --g G --spp N
--seed S --out FILE.exr. A homogeneous sphere (radius 1, sigma_s 2, sigma_a 0.05, grey) as a
volume-only material (no surface shader: the boundary is index matched), a sun of irradiance
20/27 travelling along -(1, 1, 1)/sqrt(3) with no angular size (the reference's directional
light), a pinhole camera at (0, 0, 4) looking at the origin with a 40 degree vertical field of
view, 64 x 64 pixels sampled at their centres (a box filter of 0.01 pixel, as the reference
samples each pixel's centre), black world, 1024 bounces of every kind, no clamping, no denoiser,
no adaptive sampling. Writes linear float EXR.
"""
import argparse
import math
import sys

import bpy
from mathutils import Vector

args = argparse.ArgumentParser()
args.add_argument("--g", type=float, default=0.0)
args.add_argument("--spp", type=int, default=256)
args.add_argument("--seed", type=int, default=1)
args.add_argument("--size", type=int, default=64)
args.add_argument("--segments", type=int, default=96)  # the reference's "detail"
args.add_argument("--out", required=True)
a = args.parse_args(sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else [])

bpy.ops.wm.read_factory_settings(use_empty=True)
scene = bpy.context.scene

# The medium: sigma_s = Volume Scatter density x colour, sigma_a = Volume Absorption density x
# (1 - colour) in Cycles' nodes.
# The reference's own triangles (scene/shapes.cpp, sphere_mesh): the same facets, so that the
# silhouette pixels, whose chords run through single facets, see the same geometry.
def sphere_mesh(detail, radius=1.0):
    rings, cols = max(4, detail // 2), max(6, detail)
    verts = [(0.0, radius, 0.0)]
    for r in range(1, rings):
        th = math.pi * r / rings
        for c in range(cols):
            ph = 2 * math.pi * c / cols
            verts.append((radius * math.sin(th) * math.cos(ph), radius * math.cos(th),
                          -radius * math.sin(th) * math.sin(ph)))
    verts.append((0.0, -radius, 0.0))
    south = len(verts) - 1
    ring = lambda r, c: 1 + (r - 1) * cols + (c % cols)
    faces = []
    for c in range(cols):
        faces.append((0, ring(1, c), ring(1, c + 1)))
        faces.append((south, ring(rings - 1, c + 1), ring(rings - 1, c)))
    for r in range(1, rings - 1):
        for c in range(cols):
            faces.append((ring(r, c), ring(r + 1, c), ring(r + 1, c + 1)))
            faces.append((ring(r, c), ring(r + 1, c + 1), ring(r, c + 1)))
    def volume(f):
        (ax, ay, az), (bx, by, bz), (cx, cy, cz) = (verts[i] for i in f)
        return ax * (by * cz - bz * cy) - ay * (bx * cz - bz * cx) + az * (bx * cy - by * cx)
    if sum(volume(f) for f in faces) < 0:  # outward, as Mesh::orient_outwards makes it
        faces = [(f[0], f[2], f[1]) for f in faces]
    mesh = bpy.data.meshes.new("sphere")
    mesh.from_pydata(verts, [], faces)
    mesh.update()
    return mesh


sphere = bpy.data.objects.new("sphere", sphere_mesh(a.segments))
scene.collection.objects.link(sphere)
mat = bpy.data.materials.new("medium")
mat.use_nodes = True
nodes, links = mat.node_tree.nodes, mat.node_tree.links
nodes.clear()
out = nodes.new("ShaderNodeOutputMaterial")
scatter = nodes.new("ShaderNodeVolumeScatter")
scatter.inputs["Color"].default_value = (1, 1, 1, 1)
scatter.inputs["Density"].default_value = 2.0
scatter.inputs["Anisotropy"].default_value = a.g
absorb = nodes.new("ShaderNodeVolumeAbsorption")
absorb.inputs["Color"].default_value = (0, 0, 0, 1)
absorb.inputs["Density"].default_value = 0.05
add = nodes.new("ShaderNodeAddShader")
links.new(scatter.outputs[0], add.inputs[0])
links.new(absorb.outputs[0], add.inputs[1])
links.new(add.outputs[0], out.inputs["Volume"])
mat.cycles.homogeneous_volume = True
mat.cycles.volume_sampling = "DISTANCE"
sphere.data.materials.append(mat)

# The sun: Cycles' sun shines along its local -Z; strength is irradiance (W/m^2).
sun_data = bpy.data.lights.new("sun", type="SUN")
sun_data.energy = 20.0 / 27.0
sun_data.angle = 0.0
sun = bpy.data.objects.new("sun", sun_data)
scene.collection.objects.link(sun)
travel = Vector((-1.0, -1.0, -1.0)).normalized()
sun.rotation_euler = travel.to_track_quat("-Z", "Y").to_euler()

cam_data = bpy.data.cameras.new("camera")
cam_data.sensor_fit = "VERTICAL"
cam_data.angle_y = math.radians(40.0)
cam = bpy.data.objects.new("camera", cam_data)
scene.collection.objects.link(cam)
cam.location = (0.0, 0.0, 4.0)  # looks along -Z with +Y up: at the origin
scene.camera = cam

world = bpy.data.worlds.new("black")
world.use_nodes = True
world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.0
scene.world = world

scene.render.engine = "CYCLES"
c = scene.cycles
c.device = "CPU"
c.samples = a.spp
c.seed = a.seed
c.use_adaptive_sampling = False
c.use_denoising = False
c.sample_clamp_direct = 0.0
c.sample_clamp_indirect = 0.0
c.max_bounces = 1024
c.volume_bounces = 1024
c.transparent_max_bounces = 1024
c.diffuse_bounces = c.glossy_bounces = c.transmission_bounces = 1024
c.pixel_filter_type = "BOX"
c.filter_width = 0.01
scene.render.filter_size = 0.01  # the film filter Blender 3.4 hands Cycles
c.caustics_reflective = c.caustics_refractive = True
c.blur_glossy = 0.0
scene.render.resolution_x = scene.render.resolution_y = a.size
scene.render.resolution_percentage = 100
scene.render.film_transparent = False
scene.view_settings.view_transform = "Standard"
scene.view_settings.look = "None"
scene.view_settings.exposure = 0.0
scene.render.image_settings.file_format = "OPEN_EXR"
scene.render.image_settings.color_depth = "32"
scene.render.image_settings.exr_codec = "ZIP"
scene.render.filepath = a.out
bpy.ops.render.render(write_still=True)
