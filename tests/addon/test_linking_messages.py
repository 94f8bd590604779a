"""What the render says of emitters by their ray visibility: a lamp or an emissive mesh only
Transmission rays see (camera rays past glass, the README's rule) is kept, not skipped as
lighting "nothing here, where every surface is diffuse", and an emissive mesh kept so does not
make the render claim there are no emissive materials; a lamp no ray kind sees is skipped with
a message that names Transmission too."""
import math

from . import scenes


def _pane():
    glass, nt, out = scenes._material("Glass")
    g = nt.nodes.new('ShaderNodeBsdfGlass')
    g.inputs['IOR'].default_value = 1.0
    nt.links.new(g.outputs[0], out.inputs['Surface'])
    scenes.plane("Pane", size=6, location=(0, -2, 0), materials=[glass]).rotation_euler = (math.pi / 2, 0, 0)


def _render(scene):
    scene.dacrt.samples = 1
    return scenes.render_rgba(scene)


def test_a_lamp_only_transmission_rays_see_is_kept(scene, said):
    scenes.camera((0, -5, 0), rotation=(math.pi / 2, 0, 0))
    _pane()
    lamp = scenes.light('AREA', 30.0, rotation=(-math.pi / 2, 0, 0), size=1.5, name="Panel")
    lamp.visible_camera = lamp.visible_diffuse = False
    img = _render(scene)
    assert not [t for t in said if "skipped 'Panel'" in t or "'Panel'" in t and "light nothing" in t], said
    assert img[..., :3].max() > 1.0                     # seen through the pane


def test_a_lamp_only_transmission_rays_see_without_glass(scene, said):
    scenes.camera((0, -5, 0), rotation=(math.pi / 2, 0, 0))
    scenes.plane("Floor", size=10, location=(0, 0, -1))
    lamp = scenes.light('AREA', 30.0, rotation=(-math.pi / 2, 0, 0), size=1.5, name="Panel")
    lamp.visible_camera = lamp.visible_diffuse = False
    _render(scene)
    texts = [t for t in said if "Panel" in t and "light nothing here" in t]
    assert len(texts) == 1 and "nor camera rays past glass" in texts[0], said
    assert "keep their share of the light choice" in texts[0], said


def test_a_lamp_no_ray_kind_sees_keeps_its_share_of_the_light_choice(scene, said):
    """Cycles keeps it in its light choice, where it lowers the other lights' MIS weights
    (tests/parity/test_split_occluders.py): no longer skipped at export (it had been, said
    naming its camera, diffuse and transmission visibility)."""
    scenes.camera((0, -5, 0), rotation=(math.pi / 2, 0, 0))
    scenes.plane("Floor", size=10, location=(0, 0, -1))
    lamp = scenes.light('AREA', 30.0, size=1.5, name="Panel")
    lamp.visible_camera = lamp.visible_diffuse = lamp.visible_transmission = False
    img = _render(scene)
    assert not [t for t in said if "skipped 'Panel'" in t], said
    texts = [t for t in said if "Panel" in t and "light nothing here" in t]
    assert len(texts) == 1 and "keep their share of the light choice" in texts[0], said
    assert img[..., :3].max() == 0.0


def test_an_emissive_mesh_only_transmission_rays_see_is_kept(scene, said):
    scenes.camera((0, -5, 0), rotation=(math.pi / 2, 0, 0))
    _pane()
    glow = scenes.plane("Glow", size=1.5, materials=[scenes.emission("Glow", (1, 0.5, 0.2), 3.0)])
    glow.rotation_euler = (math.pi / 2, 0, 0)
    glow.visible_camera = glow.visible_diffuse = glow.visible_shadow = False
    img = _render(scene)
    assert not [t for t in said if "no emissive materials" in t], said
    assert img[..., :3].max() > 0.5                     # seen through the pane
