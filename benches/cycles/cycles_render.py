# Renders a vastocean PLY mesh with Blender Cycles as `vastocean render --normals vertex` renders
# it: equirectangular camera 2 m above the mesh's origin (the mesh is centred under the camera,
# y up, heights from the mean sea level there), looking along +x with the sky map's azimuths, the same sky map,
# a smooth (vertex-normal) water surface with a Fresnel glass BSDF of IOR 1.333, and the same
# size, samples, bounces and threads. Prints the render time Cycles spent (scene sync, BVH build
# and path tracing; not Blender's start-up or the PLY import) as `cycles_render_seconds S`.
#
#   blender -b --factory-startup -P cycles_render.py -- MESH.ply SKY.exr OUT.png WIDTH SPP THREADS
import sys
import time

import bpy

mesh_path, sky_path, out_path, width, spp, threads = sys.argv[sys.argv.index("--") + 1 :]
width, spp, threads = int(width), int(spp), int(threads)

bpy.ops.wm.read_factory_settings(use_empty=True)
# the PLY is y up: Blender is z up
bpy.ops.import_mesh.ply(filepath=mesh_path)
ocean = bpy.context.selected_objects[0]
ocean.rotation_euler = (1.5707963267948966, 0.0, 0.0)
for poly in ocean.data.polygons:
    poly.use_smooth = True

water = bpy.data.materials.new("water")
water.use_nodes = True
nodes = water.node_tree.nodes
nodes.clear()
glass = nodes.new("ShaderNodeBsdfGlass")
glass.distribution = "SHARP"
glass.inputs["IOR"].default_value = 1.333
glass.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
out = nodes.new("ShaderNodeOutputMaterial")
water.node_tree.links.new(glass.outputs["BSDF"], out.inputs["Surface"])
ocean.data.materials.append(water)

world = bpy.data.worlds.new("sky")
world.use_nodes = True
env = world.node_tree.nodes.new("ShaderNodeTexEnvironment")
env.image = bpy.data.images.load(sky_path)
world.node_tree.links.new(env.outputs["Color"], world.node_tree.nodes["Background"].inputs["Color"])
scene = bpy.context.scene
scene.world = world

cam_data = bpy.data.cameras.new("panorama")
cam_data.type = "PANO"
cam_data.cycles.panorama_type = "EQUIRECTANGULAR"
cam = bpy.data.objects.new("camera", cam_data)
# level, the image centre along the mesh's +x (Blender's +x: the rotation maps y up to z up)
cam.rotation_euler = (1.5707963267948966, 0.0, -1.5707963267948966)
cam.location = (0.0, 0.0, 2.0)
scene.collection.objects.link(cam)
scene.camera = cam

scene.render.engine = "CYCLES"
scene.cycles.device = "CPU"
scene.cycles.samples = spp
scene.cycles.use_adaptive_sampling = False
scene.cycles.use_denoising = False
scene.cycles.max_bounces = 10
scene.cycles.glossy_bounces = 10
scene.cycles.transmission_bounces = 10
scene.render.threads_mode = "FIXED"
scene.render.threads = threads
scene.render.resolution_x = width
scene.render.resolution_y = width // 2
scene.render.resolution_percentage = 100
scene.render.filepath = out_path

start = time.perf_counter()
bpy.ops.render.render(write_still=True)
print(f"cycles_render_seconds {time.perf_counter() - start:.3f}")
