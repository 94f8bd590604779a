"""Registration: the engine, scene.dacrt, panels; installed-extension import; refusal to
register when the native binary does not match Blender's Python."""
import os
import shutil
import subprocess
import sys
import textwrap
from types import SimpleNamespace

import bpy
import pytest

from addon import ui

from . import conftest


def test_engine_is_registered_and_selectable(scene):
    engines = {getattr(e, 'bl_idname', ''): e for e in bpy.types.RenderEngine.__subclasses__()}
    assert 'DACRT' in engines
    e = engines['DACRT']
    assert e.bl_label == 'DACRT' and e.bl_use_preview is False
    assert e.bl_use_shading_nodes_custom is False
    scene.render.engine = 'CYCLES'
    scene.render.engine = 'DACRT'
    assert scene.render.engine == 'DACRT'


def test_scene_settings_defaults_and_validation(scene):
    d = scene.dacrt
    assert (d.samples, d.max_bounces, d.filter_type, d.filter_width, d.seed, d.partition) == \
        (64, 4, 'BLACKMAN_HARRIS', 1.5, 0, 'ADAPTIVE')
    assert {i.identifier for i in d.bl_rna.properties['filter_type'].enum_items} == \
        {'BOX', 'GAUSSIAN', 'BLACKMAN_HARRIS'}
    assert {i.identifier for i in d.bl_rna.properties['partition'].enum_items} == \
        {'ADAPTIVE', 'MEDIAN', 'SAH'}
    with pytest.raises(TypeError):
        d.filter_type = 'MITCHELL'
    d.samples = 0
    assert d.samples == 1                     # clamped to the minimum
    d.max_bounces = -3
    assert d.max_bounces == 0
    # saved with the file like scene.cycles
    assert scene.bl_rna.properties['dacrt'].fixed_type.identifier == 'DACRTSceneSettings'


def test_panels_shown_for_the_engine(scene):
    assert 'DACRT' in bpy.context.engine or bpy.context.engine == 'DACRT'
    assert bpy.types.RENDER_PT_dacrt.poll(bpy.context)
    for name in ('RENDER_PT_format', 'RENDER_PT_output', 'RENDER_PT_color_management',
                 'RENDER_PT_frame_range', 'DATA_PT_context_light',
                 'WORLD_PT_context_world', 'EEVEE_MATERIAL_PT_context_material',
                 'OBJECT_PT_visibility', 'DATA_PT_lens', 'DATA_PT_camera_dof',
                 'DATA_PT_camera_dof_aperture'):
        assert 'DACRT' in getattr(bpy.types, name).COMPAT_ENGINES, name
    for name in ('DATA_PT_dacrt_light', 'MATERIAL_PT_dacrt_surface', 'WORLD_PT_dacrt_surface',
                 'VIEWLAYER_PT_dacrt_passes', 'DATA_PT_dacrt_panorama'):
        assert hasattr(bpy.types, name), name
    # a child of a panel hidden for DACRT would never draw: Beam Shape (DATA_PT_spot) sits
    # under EEVEE's light panel, so the spot's cone is in DACRT's own light panel
    for panel in ui.generic_panels():
        parent = getattr(bpy.types, getattr(panel, 'bl_parent_id', '') or '', None)
        if parent is not None and hasattr(parent, 'COMPAT_ENGINES'):
            assert 'DACRT' in parent.COMPAT_ENGINES, (panel.__name__, parent.__name__)
    assert 'DACRT' not in bpy.types.DATA_PT_spot.COMPAT_ENGINES
    drawn = _drawn_props(bpy.types.DATA_PT_dacrt_light, light=bpy.data.lights.new("Spot", 'SPOT'))
    assert {'spot_size', 'spot_blend', 'show_cone'} <= drawn, drawn
    scene.render.engine = 'CYCLES'
    assert not bpy.types.RENDER_PT_dacrt.poll(bpy.context)


def _drawn_props(panel, **context):
    """The property names a panel's draw puts in its layout, with a recording layout and the
    given context members."""
    drawn = set()

    class Layout:
        use_property_split = use_property_decorate = False

        def prop(self, data, name, **kw):
            drawn.add(name)

        def __getattr__(self, name):            # row(), column(), split(), ...: the same recorder
            return lambda *a, **kw: self

    fake = SimpleNamespace(layout=Layout())
    panel.draw(fake, SimpleNamespace(**context))
    return drawn


def run_python(code, tmp_path):
    """Run code in a fresh interpreter (a second registration cannot share this process)."""
    script = tmp_path / "script.py"
    script.write_text(textwrap.dedent(code))
    env = dict(os.environ, PYTHONPATH="")
    return subprocess.run([sys.executable, str(script)], capture_output=True, text=True,
                          timeout=300, cwd=str(tmp_path), env=env)


def test_installed_as_extension_with_relative_imports(tmp_path):
    repo = tmp_path / "repo"
    shutil.copytree(conftest.ROOT / "addon", repo / "dacrt",
                    ignore=shutil.ignore_patterns("__pycache__"))
    out = run_python(f"""
        import bpy, addon_utils, sys
        assert 'addon' not in sys.modules
        bpy.context.preferences.extensions.repos.new(name="dev", module="dev",
                                                     custom_directory={str(repo)!r}, source='USER')
        addon_utils.enable("bl_ext.dev.dacrt", default_set=True, handle_error=None)
        engines = [getattr(e, 'bl_idname', '') for e in bpy.types.RenderEngine.__subclasses__()]
        assert 'DACRT' in engines, engines
        assert 'addon' not in sys.modules, "no absolute import of the checkout package"
        sc = bpy.context.scene
        sc.render.engine = 'DACRT'
        print("SAMPLES", sc.dacrt.samples)
        addon_utils.disable("bl_ext.dev.dacrt", default_set=True, handle_error=None)
        assert not hasattr(sc, 'dacrt')
        try:
            sc.render.engine = 'CYCLES'
            sc.render.engine = 'DACRT'
            print("STILL SELECTABLE")
        except TypeError:
            pass
        print("OK")
    """, tmp_path)
    assert out.returncode == 0, out.stdout + out.stderr
    assert "SAMPLES 64" in out.stdout and "OK" in out.stdout


def test_refuses_to_register_with_a_binary_for_another_python(tmp_path):
    fake = tmp_path / "site"
    fake.mkdir()
    (fake / "dacrt.cpython-313-x86_64-linux-gnu.so").write_bytes(b"not for this python")
    out = run_python(f"""
        import sys
        sys.modules['dacrt'] = None          # the matching binary is absent
        sys.path[:0] = [{str(conftest.ROOT)!r}, {str(fake)!r}]
        import bpy, addon
        try:
            addon.register()
        except ImportError as e:
            print("REFUSED:", e)
        engines = [getattr(e, 'bl_idname', '') for e in bpy.types.RenderEngine.__subclasses__()]
        print("REGISTERED" if 'DACRT' in engines or hasattr(bpy.types.Scene, 'dacrt') else "CLEAN")
    """, tmp_path)
    assert out.returncode == 0, out.stdout + out.stderr
    assert "REFUSED:" in out.stdout and "CLEAN" in out.stdout
    line = next(l for l in out.stdout.splitlines() if l.startswith("REFUSED:"))
    assert "Python 3.13" in line and f"Python {sys.version_info.major}.{sys.version_info.minor}" in line


def test_unregister_then_register_again(tmp_path):
    out = run_python(f"""
        import sys
        sys.path.insert(0, {str(conftest.ROOT)!r})
        import bpy, addon
        from addon.export import worldkeep
        for _ in range(2):
            addon.register()
            assert hasattr(bpy.types.Scene, 'dacrt') and hasattr(bpy.types, 'RENDER_PT_dacrt')
            assert bpy.app.handlers.load_post.count(worldkeep.released_on_load) == 1
            addon.unregister()
            assert not hasattr(bpy.types.Scene, 'dacrt')
            assert worldkeep.released_on_load not in bpy.app.handlers.load_post
            assert worldkeep.released_on_load not in bpy.app.handlers.load_factory_startup_post
            assert 'DACRT' not in bpy.types.RENDER_PT_format.COMPAT_ENGINES
        print("OK")
    """, tmp_path)
    assert out.returncode == 0 and "OK" in out.stdout, out.stdout + out.stderr


class FakeLayout:
    """Records what a panel draws; fails on properties the data does not have."""
    def __init__(self):
        self.drawn = []
        self.use_property_split = self.use_property_decorate = False
        self.active = self.enabled = True

    def prop(self, data, name, **_):
        assert hasattr(data, name), f"{type(data).__name__} has no property {name!r}"
        self.drawn.append(name)

    def template_node_view(self, ntree, node, socket):
        assert socket.name == 'Surface' and node.bl_idname.startswith('ShaderNodeOutput')
        self.drawn.append('node_view')

    def label(self, **_):
        self.drawn.append('label')

    def prop_search(self, data, name, search_data, search_name, **_):
        assert hasattr(data, name) and hasattr(search_data, search_name), name
        self.drawn.append(name)

    def template_list(self, list_type, list_id, data, name, active_data, active_name, **_):
        assert hasattr(data, name) and hasattr(active_data, active_name), name
        self.drawn.append(name)

    def operator(self, idname, **_):
        self.drawn.append(idname)
        return SimpleNamespace()

    def menu(self, idname, **_):
        self.drawn.append(idname)

    def separator(self, **_):
        pass

    def row(self, **_):
        return self

    def column(self, **_):
        return self

    def grid_flow(self, **_):
        return self


def test_panels_draw_existing_properties(scene):
    from . import scenes
    light = scenes.light('AREA', 10.0).data
    mat = scenes.diffuse("M", (1, 1, 1))
    world = scenes.world((1, 1, 1))
    ctx = SimpleNamespace(scene=scene, view_layer=bpy.context.view_layer, light=light,
                          material=mat, world=world, engine='DACRT')
    drawn = {}
    for name in ('RENDER_PT_dacrt', 'VIEWLAYER_PT_dacrt_passes', 'DATA_PT_dacrt_light',
                 'MATERIAL_PT_dacrt_surface', 'WORLD_PT_dacrt_surface'):
        panel = getattr(bpy.types, name)
        assert panel.poll(ctx)
        layout = FakeLayout()
        panel.draw(SimpleNamespace(layout=layout), ctx)
        drawn[name] = layout.drawn
    assert {'samples', 'max_bounces', 'filter_type', 'filter_width', 'seed', 'partition',
            'threads_mode', 'threads'} <= set(drawn['RENDER_PT_dacrt'])
    assert {'use_pass_z', 'use_pass_normal', 'use_pass_diffuse_color', 'use_pass_mist'} <= \
        set(drawn['VIEWLAYER_PT_dacrt_passes'])
    assert {'energy', 'color', 'shape', 'size', 'spread'} <= set(drawn['DATA_PT_dacrt_light'])
    assert drawn['MATERIAL_PT_dacrt_surface'] == ['node_view'] == drawn['WORLD_PT_dacrt_surface']
    for kind in ('POINT', 'SPOT', 'SUN'):
        light.type = kind
        ctx.light = bpy.data.lights[light.name]          # the RNA subtype follows the type
        layout = FakeLayout()
        bpy.types.DATA_PT_dacrt_light.draw(SimpleNamespace(layout=layout), ctx)
        assert 'energy' in layout.drawn
    cam = bpy.data.cameras.new("Cam")
    ctx.camera = cam
    assert not bpy.types.DATA_PT_dacrt_panorama.poll(ctx)          # perspective: the Lens panel
    cam.type = 'PANO'
    want = {'EQUIRECTANGULAR': {'latitude_min', 'latitude_max', 'longitude_min', 'longitude_max'},
            'FISHEYE_EQUISOLID': {'fisheye_lens', 'fisheye_fov'}, 'FISHEYE_EQUIDISTANT': {'fisheye_fov'},
            'MIRRORBALL': set(), 'EQUIANGULAR_CUBEMAP_FACE': set(),
            'CENTRAL_CYLINDRICAL': {'central_cylindrical_range_u_min', 'central_cylindrical_range_u_max',
                                    'central_cylindrical_range_v_min', 'central_cylindrical_range_v_max',
                                    'central_cylindrical_radius'}}
    for kind, props in want.items():
        cam.panorama_type = kind
        assert bpy.types.DATA_PT_dacrt_panorama.poll(ctx)
        layout = FakeLayout()
        bpy.types.DATA_PT_dacrt_panorama.draw(SimpleNamespace(layout=layout), ctx)
        assert set(layout.drawn) == {'panorama_type'} | props, (kind, layout.drawn)


def test_every_setting_the_render_reads_has_a_panel(scene):
    """What the export reads from Blender (the README's settings) is drawn by a panel shown for
    DACRT: its own, or a generic one enabled for it; Blender's Light panel, which DACRT
    replaces, stays hidden though Blender's node editor copy shares its engine set."""
    from . import scenes
    light_ob = scenes.light('AREA', 10.0)
    ctx = SimpleNamespace(scene=scene, view_layer=bpy.context.view_layer, light=light_ob.data,
                          material=scenes.diffuse("M", (1, 1, 1)), world=scenes.world((1, 1, 1)),
                          object=scenes.cube("C"), engine='DACRT')
    scene.view_layers[0].use_pass_mist = True
    drawn = {}
    from addon import ui
    names = [c.__name__ for c in ui.CLASSES] + ['VIEWLAYER_PT_override', 'OBJECT_PT_shadow_terminator',
                                                'OBJECT_PT_visibility']
    for name in names:
        panel = getattr(bpy.types, name)
        assert 'DACRT' in panel.COMPAT_ENGINES, name
        if not panel.poll(ctx):                 # (the panorama panel: no camera here)
            continue
        layout = FakeLayout()
        panel.draw(SimpleNamespace(layout=layout), ctx)
        for prop in layout.drawn:
            drawn.setdefault(prop, name)
    wanted = {  # the view layer's overrides, filter, AOVs, light groups and data-pass threshold
        'material_override', 'world_override', 'samples', 'use_sky', 'use_solid', 'use_strand',
        'aovs', 'lightgroups', 'pass_alpha_threshold',
        # the object's ray visibility, holdout, light group and shadow terminator offsets
        'visible_camera', 'visible_diffuse', 'visible_shadow', 'visible_transmission', 'is_holdout',
        'lightgroup', 'shadow_terminator_geometry_offset', 'shadow_terminator_shading_offset',
        # the light's bounces and MIS, the material's emission sampling and pass index, the
        # world's ray visibility and mist
        'max_bounces', 'use_multiple_importance_sampling', 'emission_sampling', 'pass_index',
        'use_transparent_shadow',
        'camera', 'diffuse', 'transmission', 'start', 'depth', 'falloff'}
    assert wanted <= set(drawn), sorted(wanted - set(drawn))
    # the world's own: ray visibility with Transmission and Max Bounces (both read by the render,
    # neither had been shown)
    layout = FakeLayout()
    bpy.types.WORLD_PT_dacrt_settings.draw(SimpleNamespace(layout=layout), ctx)
    assert {'camera', 'diffuse', 'transmission', 'max_bounces'} <= set(layout.drawn), layout.drawn
    assert 'DACRT' not in bpy.types.DATA_PT_light.COMPAT_ENGINES
    assert 'DACRT' not in getattr(bpy.types, 'NODE_DATA_PT_light', bpy.types.DATA_PT_light).COMPAT_ENGINES
