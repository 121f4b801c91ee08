"""Write the glTF fixtures of tests/data/blender/ with Blender's own glTF exporter (run by tools/blender_scenes).

    blender -b --factory-startup --python tools/blender_scenes.py -- OUT_DIR      (Blender 3.4, Debian 12's)
    target/bpy/bin/python tools/blender_scenes.py -- OUT_DIR                       (the current Blender's `bpy`)

One script serves both: where the Principled BSDF's inputs, the exporter's helpers, auto smooth and the actions'
F-curves moved between them, it asks which Blender runs it.

Each scene is built here in Blender (Z up, meters, 24 fps), as a user would build it in the UI, and exported with the
exporter's defaults except where a comment says why. A scene that animates is also exported still at a few frames
(`NAME@FRAME.glb`, animations off): Blender's own evaluation of the pose, which `render --time FRAME/24` of the
animated file must reproduce.
"""
import json
import math
import os
import sys

import bpy  # first: as a Python module (the current Blender's `bpy`), it brings bmesh and mathutils
import bmesh
from mathutils import Vector

# Blender 4.2 and later: the exporter's helpers were renamed, the Principled BSDF's inputs too.
NEW = bpy.app.version >= (4, 0, 0)
if NEW:
    from io_scene_gltf2.blender.com.material_helpers import create_settings_group
else:
    from io_scene_gltf2.blender.com.gltf2_blender_material_helpers import create_settings_group
TRANSMISSION = "Transmission Weight" if NEW else "Transmission"

OUT = sys.argv[sys.argv.index("--") + 1]
FPS = 24
# What Blender says of each exported scene, for the tests (blender.json): per file, per frame, each mesh object's
# world-space bounds (glTF axes: x, z, -y of Blender's) and triangle count as Blender evaluates them, and the
# lights' power.
FACTS = {}


def reset():
    bpy.ops.wm.read_factory_settings(use_empty=True)
    sc = bpy.context.scene
    sc.render.fps = FPS
    sc.frame_start = 1
    sc.frame_end = 48
    # The cameras' aspect ratio (the exporter writes it): 16:9.
    sc.render.resolution_x = 640
    sc.render.resolution_y = 360


def link(ob):
    bpy.context.scene.collection.objects.link(ob)
    return ob


def active():
    return bpy.context.view_layer.objects.active


def principled(name):
    m = bpy.data.materials.new(name)
    m.use_nodes = True
    return m, m.node_tree.nodes["Principled BSDF"]


def glass(name, ior=1.45):
    m, b = principled(name)
    b.inputs["Metallic"].default_value = 0.0
    b.inputs["Roughness"].default_value = 0.0
    b.inputs["IOR"].default_value = ior
    b.inputs[TRANSMISSION].default_value = 1.0
    return m


def colored_glass(name, color, density, ior=1.5):
    """Glass with a Volume Absorption node and the exporter's settings group (KHR_materials_volume)."""
    m = glass(name, ior)
    nodes, links = m.node_tree.nodes, m.node_tree.links
    absorb = nodes.new("ShaderNodeVolumeAbsorption")
    absorb.inputs["Color"].default_value = (*color, 1.0)
    absorb.inputs["Density"].default_value = density
    links.new(absorb.outputs["Volume"], nodes["Material Output"].inputs["Volume"])
    group = nodes.new("ShaderNodeGroup")
    group.node_tree = create_settings_group("glTF Material Output")
    group.inputs["Thickness"].default_value = 0.3
    # A volume is closed: its material is one-sided (the validator warns of a double-sided volume).
    m.use_backface_culling = True
    return m


def diffuse(name, rgb):
    m, b = principled(name)
    b.inputs["Base Color"].default_value = (*rgb, 1.0)
    b.inputs["Metallic"].default_value = 0.0
    b.inputs["Roughness"].default_value = 0.6
    return m


def mirror(name):
    m, b = principled(name)
    b.inputs["Base Color"].default_value = (0.9, 0.9, 0.9, 1.0)
    b.inputs["Metallic"].default_value = 1.0
    b.inputs["Roughness"].default_value = 0.0
    return m


def give(ob, m):
    ob.data.materials.clear()
    ob.data.materials.append(m)
    return ob


def smooth(ob):
    for p in ob.data.polygons:
        p.use_smooth = True
    return ob


def floor(size=4.0):
    bpy.ops.mesh.primitive_plane_add(size=size, location=(0, 0, 0))
    ob = active()
    ob.name = "Floor"
    return give(ob, diffuse("Floor", (0.8, 0.8, 0.8)))


def spot(location=(0, 0, 2.2), power=60.0, size_deg=70.0, blend=0.15, name="Spot"):
    light = bpy.data.lights.new(name, "SPOT")
    light.energy = power
    light.spot_size = math.radians(size_deg)
    light.spot_blend = blend
    ob = link(bpy.data.objects.new(name, light))
    ob.location = location
    # A light shines down its -Z: straight down.
    return ob


def cameras(main_location=(2.6, -2.6, 2.0), target=(0, 0, 0.4)):
    """A perspective `Camera` aimed at `target`, and an orthographic `Top` looking straight down (its image's up is
    Blender's +Y, glTF's -Z)."""
    cam = bpy.data.cameras.new("Camera")
    cam.lens = 40
    ob = link(bpy.data.objects.new("Camera", cam))
    ob.location = main_location
    direction = Vector(target) - Vector(main_location)
    ob.rotation_euler = direction.to_track_quat("-Z", "Y").to_euler()
    top = bpy.data.cameras.new("Top")
    top.type = "ORTHO"
    top.ortho_scale = 4.0
    t = link(bpy.data.objects.new("Top", top))
    t.location = (0, 0, 4.0)
    return ob, t


def fcurves(anim_data):
    """An animation's F-curves: the action's own before Blender 4.4, its slot's channel bag since (layered actions;
    Blender 5 has no `Action.fcurves`)."""
    action = anim_data.action
    if hasattr(action, "fcurves"):
        return action.fcurves
    from bpy_extras import anim_utils

    bag = anim_utils.action_get_channelbag_for_slot(action, anim_data.action_slot)
    return bag.fcurves if bag else []


def auto_smooth(ob):
    """Sharp edges over 30° (Blender's auto smooth; a modifier since 4.1, after the others as auto smooth was)."""
    if hasattr(ob.data, "use_auto_smooth"):
        ob.data.use_auto_smooth = True
        return
    bpy.ops.object.select_all(action="DESELECT")
    ob.select_set(True)
    bpy.context.view_layer.objects.active = ob
    bpy.ops.object.shade_auto_smooth(angle=math.radians(30))


def key(ob, path, frames_values, index=-1):
    """Keyframes of `ob.path` at (frame, value), linear between them."""
    for frame, value in frames_values:
        setattr(ob, path, value)
        ob.keyframe_insert(path, frame=frame, index=index)
    data = ob.animation_data if hasattr(ob, "animation_data") else None
    if data and data.action:
        for fc in fcurves(data):
            for kp in fc.keyframe_points:
                kp.interpolation = "LINEAR"


def facts(name, frames):
    """Blender's own evaluation of the scene at each of `frames`."""
    sc = bpy.context.scene
    out = {"frames": {}, "lights": {}}
    for f in frames:
        sc.frame_set(f)
        depsgraph = bpy.context.evaluated_depsgraph_get()
        objects = {}
        for ob in sc.objects:
            if ob.type != "MESH":
                continue
            ev = ob.evaluated_get(depsgraph)
            me = ev.to_mesh()
            me.calc_loop_triangles()
            pts = [ev.matrix_world @ v.co for v in me.vertices]
            gl = [(p.x, p.z, -p.y) for p in pts]
            lo = [min(p[k] for p in gl) for k in range(3)]
            hi = [max(p[k] for p in gl) for k in range(3)]
            objects[ob.name] = {"min": lo, "max": hi, "triangles": len(me.loop_triangles)}
            ev.to_mesh_clear()
        out["frames"][str(f)] = objects
    # The lights' power at the first frame (where an animated one starts).
    sc.frame_set(1)
    for ob in sc.objects:
        if ob.type == "LIGHT":
            out["lights"][ob.name] = {"type": ob.data.type, "watts": ob.data.energy}
    FACTS[name] = out


def export(name, apply_modifiers=False, animations=True, extras=False, pointers=False):
    path = os.path.join(OUT, name + ".glb")
    # Lights', cameras' and materials' animation as KHR_animation_pointer (Blender 4.2 and later), which the
    # exporter writes in its "Scene" animation mode only.
    more = {"export_pointer_animation": True, "export_animation_mode": "SCENE"} if pointers and animations else {}
    bpy.ops.export_scene.gltf(
        **more,
        # Custom properties as extras (the media's priorities), where a scene has them.
        export_extras=extras,
        filepath=path,
        export_format="GLB",
        export_cameras=True,
        export_lights=True,
        export_apply=apply_modifiers,
        export_animations=animations,
        # A still export is the pose at the current frame (the exporter's default is frame 0's).
        export_current_frame=not animations,
        # Every frame sampled (the exporter's default), so that the file holds Blender's own evaluation.
        export_force_sampling=True,
    )
    print("wrote", path, os.path.getsize(path), "bytes")


def export_obj(name):
    """The scene's meshes as Wavefront OBJ with its MTL materials and their textures copied beside it (the
    exporter's defaults: glTF's axes, -Z forward and Y up). Blender writes a glass material as an opaque one
    (`illum 2`, `d 1`): its OBJ export carries no transmission."""
    path = os.path.join(OUT, name + ".obj")
    bpy.ops.wm.obj_export(filepath=path, export_materials=True, path_mode="COPY")
    print("wrote", path, os.path.getsize(path), "bytes")


def export_poses(name, frames, apply_modifiers=False, pointers=False):
    """The animated scene, and Blender's still pose at each of `frames` (NAME@FRAME.glb)."""
    facts(name, frames)
    export(name, apply_modifiers, pointers=pointers)
    for f in frames:
        bpy.context.scene.frame_set(f)
        export(f"{name}@{f}", apply_modifiers, animations=False)
    bpy.context.scene.frame_set(1)


def suzanne(location, subdivisions=1, name="Suzanne", scale=0.35):
    bpy.ops.mesh.primitive_monkey_add(size=2.0, location=location)
    ob = active()
    ob.name = name
    ob.scale = (scale, scale, scale)
    smooth(ob)
    mod = ob.modifiers.new("Subdivision", "SUBSURF")
    mod.levels = subdivisions
    mod.render_levels = subdivisions
    return ob


def ball(name, radius, location=(0, 0, 0)):
    bpy.ops.mesh.primitive_uv_sphere_add(segments=32, ring_count=16, radius=radius, location=location)
    ob = active()
    ob.name = name
    return smooth(ob)


def scene_glass_modifiers():
    """A still glass Suzanne with a subdivision and a solidify-free bevel-free stack: one Subdivision Surface
    modifier (applied by the exporter), turned and lifted by her node."""
    reset()
    floor()
    s = give(suzanne((0.0, 0.0, 0.55)), glass("Glass"))
    s.rotation_euler = (math.radians(-20), 0, math.radians(30))
    spot()
    cameras()
    facts("glass_modifiers", [1])
    export("glass_modifiers", apply_modifiers=True)


def scene_two_objects():
    """Blender writes one animation per animated object: a glass Suzanne (subdivided) turning about her vertical
    axis over 2 s, and a glass ball parented to an empty that slides across in 1.5 s."""
    reset()
    floor()
    s = give(suzanne((-0.35, 0.0, 0.55), scale=0.3), glass("Glass"))
    key(s, "rotation_euler", [(1, (0, 0, 0)), (48, (0, 0, 2 * math.pi))])
    rig = link(bpy.data.objects.new("Slider", None))
    rig.location = (0.2, -0.5, 0.35)
    key(rig, "location", [(1, (0.2, -0.5, 0.35)), (36, (0.55, 0.5, 0.45))])
    b = give(ball("Ball", 0.18), glass("Ball glass", 1.5))
    b.parent = rig
    b.location = (0.05, 0.0, 0.1)
    spot()
    cameras()
    export_poses("two_objects", [1, 18, 40], apply_modifiers=True)


def scene_rig():
    """A parented, animated rig: an empty that moves and turns, a glass ball under it (its own offset, turn and
    scale, and a pulsing scale), and a glass cube under the ball that follows both."""
    reset()
    floor()
    rig = link(bpy.data.objects.new("Rig", None))
    key(rig, "location", [(1, (-0.3, 0.1, 0.3)), (48, (0.3, -0.1, 0.4))])
    key(rig, "rotation_euler", [(1, (0, 0, 0)), (48, (0, 0, math.radians(120)))])
    b = give(ball("Ball", 0.2), glass("Glass"))
    b.parent = rig
    b.location = (0.2, 0.0, 0.15)
    b.rotation_euler = (math.radians(15), 0, 0)
    key(b, "scale", [(1, (1.0, 1.0, 1.0)), (24, (1.2, 0.9, 1.1)), (48, (1.0, 1.0, 1.0))])
    bpy.ops.mesh.primitive_cube_add(size=0.15)
    c = give(active(), glass("Cube glass", 1.6))
    c.name = "Cube"
    c.parent = b
    c.location = (-0.15, 0.35, 0.3)
    c.rotation_euler = (0, math.radians(30), math.radians(10))
    spot(location=(0, 0, 2.4))
    cameras()
    export_poses("rig", [1, 20, 48])


def scene_shape_keys():
    """A glass slab whose top bulges into a lens (an animated shape key) and leans (a still one, at 0.4)."""
    reset()
    floor()
    bpy.ops.mesh.primitive_grid_add(x_subdivisions=16, y_subdivisions=16, size=0.8, location=(0, 0, 0.5))
    top = active()
    # A closed slab: the grid, extruded down.
    bpy.ops.object.mode_set(mode="EDIT")
    bpy.ops.mesh.select_all(action="SELECT")
    bpy.ops.mesh.extrude_region_move(TRANSFORM_OT_translate={"value": (0, 0, -0.12)})
    bpy.ops.mesh.select_all(action="SELECT")
    bpy.ops.mesh.normals_make_consistent(inside=False)
    bpy.ops.object.mode_set(mode="OBJECT")
    slab = smooth(give(top, glass("Glass", 1.5)))
    slab.name = "Slab"
    slab.shape_key_add(name="Basis")
    bulge = slab.shape_key_add(name="Bulge", from_mix=False)
    lean = slab.shape_key_add(name="Lean", from_mix=False)
    for i, v in enumerate(slab.data.vertices):
        co = v.co
        if co.z > -1e-6:
            r2 = (co.x * co.x + co.y * co.y) / (0.4 * 0.4)
            bulge.data[i].co = co + Vector((0, 0, 0.15 * max(0.0, 1.0 - r2)))
        lean.data[i].co = co + Vector((0.15 * co.z + 0.05 * co.y, 0, 0))
    lean.value = 0.4
    for frame, value in [(1, 0.0), (48, 1.0)]:
        bulge.value = value
        bulge.keyframe_insert("value", frame=frame)
    for fc in fcurves(slab.data.shape_keys.animation_data):
        for kp in fc.keyframe_points:
            kp.interpolation = "LINEAR"
    spot(location=(0, 0, 2.0), size_deg=60)
    cameras()
    export_poses("shape_keys", [1, 24, 48])


def prism(name, location):
    """A right triangular prism (not symmetric under x → -x)."""
    verts = [(0, 0, 0), (0.4, 0, 0), (0, 0, 0.3), (0, 0.4, 0), (0.4, 0.4, 0), (0, 0.4, 0.3)]
    faces = [(0, 2, 1), (3, 4, 5), (0, 1, 4, 3), (1, 2, 5, 4), (2, 0, 3, 5)]
    me = bpy.data.meshes.new(name)
    me.from_pydata(verts, [], faces)
    me.update()
    ob = link(bpy.data.objects.new(name, me))
    ob.location = location
    return ob


def scene_mirror(applied):
    """A steep mirror throwing a patch of the spot onto the floor beside it, and a glass prism mirrored by its node's negative x scale
    (`applied`: the same scene with the mirroring applied to the mesh, so that no node scale is negative)."""
    reset()
    floor()
    bpy.ops.mesh.primitive_plane_add(size=4.0, location=(0, 2.0, 2.0), rotation=(math.radians(90), 0, 0))
    wall = give(active(), diffuse("Wall", (0.7, 0.7, 0.7)))
    wall.name = "Wall"
    bpy.ops.mesh.primitive_plane_add(size=0.6, location=(0.5, -0.95, 0.45), rotation=(math.radians(-60), 0, 0))
    m = give(active(), mirror("Mirror"))
    m.name = "Mirror"
    p = give(prism("Prism", (-0.3, -0.4, 0.35)), glass("Glass", 1.5))
    p.scale = (-1.0, 1.0, 1.0)
    p.rotation_euler = (0, 0, math.radians(20))
    if applied:
        bpy.ops.object.select_all(action="DESELECT")
        p.select_set(True)
        bpy.context.view_layer.objects.active = p
        bpy.ops.object.transform_apply(location=False, rotation=False, scale=True)
    spot(location=(0.2, -0.35, 2.0), size_deg=100)
    cameras()
    name = "mirror_applied" if applied else "mirror"
    facts(name, [1])
    export(name)
    if applied:
        export_obj(name)


def scene_colored_glass():
    """An amber glass ball: Volume Absorption (exported as KHR_materials_volume attenuation) in clear glass."""
    reset()
    floor()
    b = give(ball("Amber", 0.3, (0, 0, 0.5)), colored_glass("Amber", (0.9, 0.55, 0.2), 2.0))
    spot()
    cameras()
    facts("colored_glass", [1])
    export("colored_glass")


def scene_skinned():
    """A glass cylinder skinned to an armature whose bone bends over the animation (the renderer has no skins: it
    stands at its bind pose, which blender.json records with the armature at rest)."""
    reset()
    floor()
    bpy.ops.object.armature_add(location=(0.1, 0.0, 0.2))
    arm = active()
    arm.name = "Armature"
    bpy.ops.mesh.primitive_cylinder_add(vertices=24, radius=0.15, depth=0.6, location=(0.1, 0.0, 0.5))
    cyl = smooth(give(active(), glass("Glass", 1.5)))
    cyl.name = "Cylinder"
    bpy.ops.object.select_all(action="DESELECT")
    cyl.select_set(True)
    arm.select_set(True)
    bpy.context.view_layer.objects.active = arm
    bpy.ops.object.parent_set(type="ARMATURE_AUTO")
    bone = arm.pose.bones[0]
    bone.rotation_mode = "XYZ"
    key(bone, "rotation_euler", [(1, (0, 0, 0)), (48, (math.radians(40), 0, 0))])
    for fc in fcurves(arm.animation_data):
        for kp in fc.keyframe_points:
            kp.interpolation = "LINEAR"
    spot()
    cameras()
    arm.data.pose_position = "REST"
    facts("skinned", [24])
    arm.data.pose_position = "POSE"
    export("skinned")


def scene_glass_of_water():
    """A glass of water as an artist models it: a tumbler (a cylinder without its top face, given 4 cm walls and base
    by a Solidify modifier) and the water in it, a cylinder reaching 1 cm into the glass's wall and base. Glass has
    no nesting of its own in glTF: each material carries a custom property `priority` (exported as its extras with
    the exporter's "Custom Properties"), the glass's 2 and the water's 1, so that where they overlap the glass is
    there. A spot to the side sends light through the wall and the water onto the floor."""
    reset()
    floor()
    bpy.ops.mesh.primitive_cylinder_add(vertices=96, radius=0.4, depth=1.0, location=(0, 0, 0.501))
    g = active()
    g.name = "Glass"
    bm = bmesh.new()
    bm.from_mesh(g.data)
    bmesh.ops.delete(bm, geom=[f for f in bm.faces if f.normal.z > 0.9], context="FACES_ONLY")
    bm.to_mesh(g.data)
    bm.free()
    solid = g.modifiers.new("Solidify", "SOLIDIFY")
    solid.thickness = 0.04
    solid.use_even_offset = True
    glass_material = glass("Glass", 1.5)
    glass_material["priority"] = 2
    smooth(give(g, glass_material))
    auto_smooth(g)
    bpy.ops.mesh.primitive_cylinder_add(vertices=96, radius=0.37, depth=0.67, location=(0, 0, 0.366))
    w = active()
    w.name = "Water"
    water_material = glass("Water", 1.33)
    water_material["priority"] = 1
    smooth(give(w, water_material))
    auto_smooth(w)
    # A wide cone: the caustic map holds what the light sees, and the caustic reaches far behind the glass.
    s = spot(location=(-1.6, 0.3, 1.6), power=120.0, size_deg=100.0)
    direction = Vector((0, 0, 0.35)) - s.location
    s.rotation_euler = direction.to_track_quat("-Z", "Y").to_euler()
    cameras(main_location=(1.8, -2.2, 1.6), target=(0.3, 0, 0.3))
    facts("glass_of_water", [1])
    export("glass_of_water", apply_modifiers=True, extras=True)


def scene_textured():
    """A floor textured by an image (8x8 blocks of distinct colors, 64 px a side, saved as PNG, UV-mapped by the
    plane's own coordinates and repeated twice along u) under a glass ball lit by a spot: the file the texture
    compressors (glTF-Transform's `webp`) start from."""
    reset()
    fl = floor()
    img = bpy.data.images.new("Blocks", 64, 64)
    px = []
    for y in range(64):
        for x in range(64):
            bx, by = x // 8, y // 8
            px += [0.15 + 0.1 * bx, 0.85 - 0.1 * by, 0.2 + 0.6 * ((bx + by) % 2), 1.0]
    img.pixels = px
    img.filepath_raw = os.path.join(bpy.app.tempdir, "blocks.png")
    img.file_format = "PNG"
    img.save()
    m = fl.data.materials[0]
    nodes, links = m.node_tree.nodes, m.node_tree.links
    tex = nodes.new("ShaderNodeTexImage")
    tex.image = img
    mapping = nodes.new("ShaderNodeMapping")
    mapping.inputs["Scale"].default_value = (2.0, 1.0, 1.0)
    coords = nodes.new("ShaderNodeTexCoord")
    links.new(coords.outputs["UV"], mapping.inputs["Vector"])
    links.new(mapping.outputs["Vector"], tex.inputs["Vector"])
    links.new(tex.outputs["Color"], nodes["Principled BSDF"].inputs["Base Color"])
    give(ball("Ball", 0.4, location=(0, 0, 0.6)), glass("Ball", 1.5))
    spot()
    cameras()
    facts("textured", [1])
    export("textured")
    export_obj("textured")


def scene_instances():
    """Four glass balls sharing one mesh (linked duplicates, as Alt+D makes them: one mesh datablock, four objects)
    and a fifth scaled and turned, over a floor, lit by a spot: the file gltfpack's `-mi` (EXT_mesh_gpu_instancing)
    starts from."""
    reset()
    floor()
    first = give(ball("Ball", 0.22, location=(-0.5, -0.5, 0.35)), glass("Ball", 1.5))
    spots = [(0.5, -0.5, 0.35), (-0.5, 0.5, 0.35), (0.5, 0.5, 0.5)]
    for k, location in enumerate(spots):
        ob = link(bpy.data.objects.new(f"Ball.{k + 1:03}", first.data))
        ob.location = location
    last = bpy.data.objects["Ball.003"]
    last.scale = (1.0, 1.4, 0.8)
    last.rotation_euler = (0.3, 0.0, 0.7)
    spot(size_deg=90.0)
    cameras()
    facts("instances", [1])
    export("instances")


def scene_light_and_lens():
    """A spot whose power, color and cone change over the animation, and a camera that zooms (its focal length
    from 30 to 60 mm), over a glass ball whose IOR falls: what KHR_animation_pointer carries (the current Blender only; 3.4's
    exporter has no pointers)."""
    reset()
    floor()
    ball_glass = glass("Ball", 1.5)
    give(ball("Ball", 0.4, location=(0, 0, 0.6)), ball_glass)
    # The glass's IOR too, from 1.5 to 1.33.
    ior = ball_glass.node_tree.nodes["Principled BSDF"].inputs["IOR"]
    for frame, value in [(1, 1.5), (48, 1.33)]:
        ior.default_value = value
        ior.keyframe_insert("default_value", frame=frame)
    light = spot(size_deg=40.0).data
    for frame, watts, color, size in [(1, 20.0, (1.0, 1.0, 1.0), 40.0), (48, 80.0, (1.0, 0.5, 0.2), 70.0)]:
        light.energy, light.color, light.spot_size = watts, color, math.radians(size)
        for path in ["energy", "color", "spot_size"]:
            light.keyframe_insert(path, frame=frame)
    cam, _ = cameras()
    for frame, lens in [(1, 30.0), (48, 60.0)]:
        cam.data.lens = lens
        cam.data.keyframe_insert("lens", frame=frame)
    for data in [light, cam.data, ball_glass.node_tree]:
        for fc in fcurves(data.animation_data):
            for kp in fc.keyframe_points:
                kp.interpolation = "LINEAR"
    export_poses("light_and_lens", [1, 20, 48], pointers=True)


os.makedirs(OUT, exist_ok=True)
scene_glass_modifiers()
scene_two_objects()
scene_rig()
scene_shape_keys()
scene_mirror(False)
scene_mirror(True)
scene_colored_glass()
scene_skinned()
scene_glass_of_water()
scene_textured()
scene_instances()
if NEW:
    scene_light_and_lens()
with open(os.path.join(OUT, "blender.json"), "w") as f:
    json.dump(FACTS, f, indent=1, sort_keys=True)
    f.write("\n")
print("wrote", os.path.join(OUT, "blender.json"))
