"""An animation, or a still rendered with write_still, cancelled through
addon.engine.request_cancel (a script's or a signal handler's cancel, which Blender's test_break
does not know) at a frame's start: that frame has no image, and Blender 5.0.1 writes it anyway.
An EXR crashed its image writer (a segfault in do_write_image_or_movie or BKE_image_render_write,
as for any engine that leaves a frame without a result); PNGs were written of nothing, in an
animation for every later frame (the cancel stays asked). The engine now reports the cancel as
an error, which stops the render: the frames before it are written, nothing else, and the process
lives. Run in a subprocess, where the crash had been a signal."""
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

    animation = sys.argv[3] == 'animation'

    def cancel_at_2(scene, *args):
        if scene.frame_current == 2 or not animation:
            engine.request_cancel()
    bpy.app.handlers.render_pre.append(cancel_at_2)
    try:
        bpy.ops.render.render(animation=animation, write_still=not animation)
        print('RESULT finished')
    except RuntimeError as e:
        print('RESULT stopped:', e)
    engine.clear_cancel()
    print('FILES', sorted(os.listdir(sys.argv[1])))
''')


@pytest.mark.parametrize('kind', ['animation', 'still'])
@pytest.mark.parametrize('file_format', ['PNG', 'OPEN_EXR'])
def test_a_cancelled_render_stops_instead_of_crashing(tmp_path, file_format, kind):
    script = tmp_path / 'cancel.py'
    script.write_text(_SCRIPT)
    out = tmp_path / 'frames'
    out.mkdir()
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(filter(None, [root, os.environ.get('PYTHONPATH')])))
    run = subprocess.run([sys.executable, str(script), str(out), file_format, kind], capture_output=True,
                         text=True, timeout=600, cwd=root, env=env)
    assert run.returncode == 0, (run.returncode, run.stdout[-2000:], run.stderr[-2000:])
    if kind == 'animation':
        assert "RESULT stopped:" in run.stdout and "render cancelled at frame 2" in run.stdout, run.stdout[-2000:]
        assert "FILES ['f0001" in run.stdout and "f0002" not in run.stdout, run.stdout[-2000:]
    else:
        assert "RESULT stopped:" in run.stdout and "nothing to write" in run.stdout, run.stdout[-2000:]
        assert "FILES []" in run.stdout, run.stdout[-2000:]


_CLI_SCRIPT = textwrap.dedent('''
    import signal, sys
    import bpy
    from addon import cli

    @bpy.app.handlers.persistent
    def ctrl_c(*args):          # (the command line's SIGINT handler, called as a Ctrl-C calls it)
        signal.getsignal(signal.SIGINT)(signal.SIGINT, None)
    bpy.app.handlers.render_pre.append(ctrl_c)
    if len(sys.argv) > 2:       # another error after the Ctrl-C
        from addon import export

        def fails(*args, **kw):
            raise {'memory': MemoryError, 'other': ValueError}[sys.argv[2]]('the export broke')
        export.export_scene = fails
    cli.main(['render', '--samples', '2', '--out', sys.argv[1]])
''')


def test_ctrl_c_before_the_command_lines_frame_had_an_image(tmp_path):
    """The command line's Ctrl-C before the frame had an image: exit 130, nothing written, said
    (it had ended 'error: could not write the image', exit 1)."""
    script = tmp_path / 'cli_cancel.py'
    script.write_text(_CLI_SCRIPT)
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(filter(None, [root, os.environ.get('PYTHONPATH')])))
    run = subprocess.run([sys.executable, str(script), str(tmp_path / 'out' / 'x.png')], capture_output=True,
                         text=True, timeout=600, cwd=root, env=env)
    assert run.returncode == 130, (run.returncode, run.stdout[-2000:], run.stderr[-2000:])
    assert "interrupted before the frame had an image; nothing written" in run.stdout, run.stdout[-2000:]
    assert not (tmp_path / 'out' / 'x.png').exists() and not (tmp_path / 'out' / 'x.exr').exists()


@pytest.mark.parametrize('error', ['other', 'memory'])
def test_another_error_after_the_command_lines_ctrl_c_keeps_its_message(tmp_path, error):
    """A render that failed otherwise after the Ctrl-C (alone, or beside the cancel's error: out of
    memory before the frame had an image) says its error, exit 1: it had been taken for the
    cancel ('nothing written', exit 130), the real message hidden."""
    script = tmp_path / 'cli_cancel.py'
    script.write_text(_CLI_SCRIPT)
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(filter(None, [root, os.environ.get('PYTHONPATH')])))
    run = subprocess.run([sys.executable, str(script), str(tmp_path / 'out' / 'x.png'), error],
                         capture_output=True, text=True, timeout=600, cwd=root, env=env)
    assert run.returncode == 1, (run.returncode, run.stdout[-2000:], run.stderr[-2000:])
    assert "nothing written" not in run.stdout, run.stdout[-2000:]
    assert "error: render failed:" in run.stderr and "the export broke" in run.stderr, run.stderr[-2000:]
