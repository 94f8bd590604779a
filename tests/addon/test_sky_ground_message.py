"""A Single Scattering Sky Texture's ground (below its horizon) fades as Cycles' published
kernel gives it; Cycles 5.0.1 renders it 2-25% darker (camera at the horizon, sun at 0.5 rad:
DACRT 1.009x -> 1.22x Cycles row by row going down; README). That was silent. It is said where
the camera sees that ground (map directions with -0.4 < z < 0): not for a view above the
horizon or straight down (black in both), nor for Multiple Scattering (exact), a transparent
film, a world hidden from camera rays, or a camera backdrop picked by Is Camera Ray."""
import math

import bpy
import pytest

from . import scenes

SAID = "Single Scattering Sky Texture's ground"


def _sky(sc, kind='SINGLE_SCATTERING', pitch=95.0, strength=1.0, backdrop=False, **camera):
    scenes.camera(location=(0, 0, 1), rotation=(math.radians(pitch), 0, 0), **camera)
    scenes.plane(size=2, location=(0, 0, -50), materials=[scenes.diffuse('floor', (0.5, 0.5, 0.5))])
    w, nt, out = scenes.world_tree(sc)
    bg = nt.nodes.new('ShaderNodeBackground')
    bg.inputs['Strength'].default_value = strength
    sky = nt.nodes.new('ShaderNodeTexSky')
    sky.sky_type, sky.sun_elevation = kind, 0.5
    nt.links.new(sky.outputs[0], bg.inputs['Color'])
    if backdrop:        # the camera sees a grey backdrop, the scene is lit by the sky
        grey = nt.nodes.new('ShaderNodeBackground')
        mix = nt.nodes.new('ShaderNodeMixShader')
        path = nt.nodes.new('ShaderNodeLightPath')
        nt.links.new(path.outputs['Is Camera Ray'], mix.inputs['Fac'])
        nt.links.new(bg.outputs[0], mix.inputs[1])
        nt.links.new(grey.outputs[0], mix.inputs[2])
        nt.links.new(mix.outputs[0], out.inputs['Surface'])
    else:
        nt.links.new(bg.outputs[0], out.inputs['Surface'])
    return w


def _said(said):
    said.clear()
    bpy.ops.render.render()
    return [t for t in said if SAID in t]


@pytest.mark.parametrize('case', ['horizon', 'equirectangular', 'orthographic_level'])
def test_said_where_the_camera_sees_the_ground(scene, said, case):
    if case == 'horizon':
        _sky(scene)
    elif case == 'equirectangular':
        _sky(scene, pitch=90.0)
        cam = scene.camera.data
        cam.type, cam.panorama_type = 'PANO', 'EQUIRECTANGULAR'
    else:                               # every ray 10 degrees down
        _sky(scene, pitch=80.0, kind='SINGLE_SCATTERING')
        scene.camera.data.type = 'ORTHO'
    got = _said(said)
    assert len(got) == 1 and "2-25% darker" in got[0], got


@pytest.mark.parametrize('case', ['above', 'straight_down', 'multiple', 'film_transparent',
                                  'camera_hidden', 'backdrop', 'dark'])
def test_not_said_where_it_cannot_show(scene, said, case):
    w = _sky(scene, kind='MULTIPLE_SCATTERING' if case == 'multiple' else 'SINGLE_SCATTERING',
             pitch={'above': 125.0, 'straight_down': 0.0}.get(case, 95.0),
             strength=0.0 if case == 'dark' else 1.0, backdrop=case == 'backdrop')
    scene.render.film_transparent = case == 'film_transparent'
    if case == 'camera_hidden':
        w.cycles_visibility.camera = False
    assert not _said(said)


@pytest.mark.parametrize('pitch, seen', [(95.0, True), (125.0, False)])
def test_said_in_the_viewport_by_its_view(scene, pitch, seen):
    # the viewport's camera (export.viewport_camera) decides it as the render camera does
    from addon import export
    from .test_viewport import _view_of
    _sky(scene, pitch=pitch)
    data = export.export_scene(bpy.context.evaluated_depsgraph_get(), view_camera=_view_of(scene.camera))
    assert any(SAID in text for _, text in data.messages) == seen, data.messages
