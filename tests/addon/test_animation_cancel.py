"""An animation cancelled through addon.engine.request_cancel (a script's or a signal handler's
cancel, which Blender's test_break does not know) at a frame's start: that frame has no image, and
Blender 5.0.1 writes it anyway: an EXR crashed its image writer (a segfault in
do_write_image_or_movie, as for any engine that leaves a frame without a result), and PNGs were
written for every later frame, none of them rendered (the cancel stays asked). The
engine now reports the cancel as an error, which stops the animation: the frames before it are
written, the process lives. Run in a subprocess, where the crash had been a signal."""
import os
import subprocess
import sys
import textwrap

import pytest

_SCRIPT = textwrap.dedent('''
    import os, sys
    import bpy
    import addon
    from addon import engine
    from tests.addon import scenes
    addon.register()
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.engine = 'DACRT'
    sc.render.resolution_x, sc.render.resolution_y = 8, 6
    sc.dacrt.samples = 1
    scenes.camera()
    scenes.plane(materials=[scenes.diffuse('grey', (0.8, 0.8, 0.8))])
    sc.frame_start, sc.frame_end = 1, 4
    sc.render.filepath = os.path.join(sys.argv[1], 'f####')
    sc.render.image_settings.file_format = sys.argv[2]

    def cancel_at_2(scene, *args):
        if scene.frame_current == 2:
            engine.request_cancel()
    bpy.app.handlers.render_pre.append(cancel_at_2)
    try:
        bpy.ops.render.render(animation=True)
        print('RESULT finished')
    except RuntimeError as e:
        print('RESULT stopped:', e)
    engine.clear_cancel()
    print('FILES', sorted(os.listdir(sys.argv[1])))
''')


@pytest.mark.parametrize('file_format', ['PNG', 'OPEN_EXR'])
def test_a_cancelled_animation_stops_instead_of_crashing(tmp_path, file_format):
    script = tmp_path / 'cancel.py'
    script.write_text(_SCRIPT)
    out = tmp_path / 'frames'
    out.mkdir()
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(filter(None, [root, os.environ.get('PYTHONPATH')])))
    run = subprocess.run([sys.executable, str(script), str(out), file_format], capture_output=True, text=True,
                         timeout=600, cwd=root, env=env)
    assert run.returncode == 0, (run.returncode, run.stdout[-2000:], run.stderr[-2000:])
    assert "RESULT stopped:" in run.stdout and "render cancelled at frame 2" in run.stdout, run.stdout[-2000:]
    assert "FILES ['f0001" in run.stdout, run.stdout[-2000:]
