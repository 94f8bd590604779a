"""Headless rendering through the bpy module: `python -m addon.cli render [scene.blend] ...`.

    python -m addon.cli render                       # the built-in demo -> render/demo.png + .exr
    python -m addon.cli render scene.blend --samples 128 --out out/shot.png

Registers the add-on, opens the .blend (or builds the demo scene), renders every enabled view
layer with DACRT and writes a PNG (view transform applied) and a linear float EXR next to each
other; the EXR is a multilayer one holding every layer and pass when more than one layer or any
pass beyond Combined was rendered (the PNG shows the composite, or the first layer's Combined
without compositing); at Pixel Aspect != 1 that one is written at aspect 1 and its parts'
PixelAspectRatio set afterwards (Blender 5.0 cannot write it). `python3 build.py render ...`
forwards here. Exit status 1 with the reason on failure.
Ctrl-C cancels the render as Esc does in Blender: the samples done so far are written and the
exit status is 130; a second Ctrl-C stops at once.
"""
import argparse
import contextlib
import os
import re
import shutil
import signal
import sys
import tempfile

import bpy

from . import engine, last_render_stats, register
from .engine import extra_passes
from .passes import NOISY_IMAGE


def parse_args(argv):
    parser = argparse.ArgumentParser(prog="python -m addon.cli",
                                     description="Render with DACRT headless through bpy.")
    sub = parser.add_subparsers(dest="command", required=True)
    render = sub.add_parser("render", help="render a .blend file, or the built-in demo scene")
    render.add_argument("blend", nargs="?", help=".blend file (default: the built-in demo scene)")
    render.add_argument("--samples", type=int, help="samples per pixel (default: the scene's)")
    render.add_argument("--out", help="output image; a .png and a .exr are written side by side "
                                      "(default: render/<scene>.png); '//' starts it at the .blend's "
                                      "folder and a run of '#' is the frame number, as in Blender")
    render.add_argument("--frame", type=int, help="frame to render (default: the current frame)")
    return parser.parse_args(argv)


def blender_path(out, frame, blend):
    """--out in Blender's path syntax, as `blender -o` reads it: a leading '//' is the .blend's
    folder (the working directory for the demo scene), and the last run of '#' in the file name
    is the frame number padded to the run's length as C's %.*d pads it (-3 in '###': '-003');
    '#' in a folder name is kept."""
    if out.startswith("//"):
        out = os.path.join(os.path.dirname(os.path.abspath(blend)) if blend else ".", out[2:])
    folder, name = os.path.split(out)
    runs = list(re.finditer(r"#+", name))
    if runs:
        m, n = runs[-1], len(runs[-1].group())
        number = f"-{-frame:0{n}d}" if frame < 0 else f"{frame:0{n}d}"
        out = os.path.join(folder, name[:m.start()] + number + name[m.end():])
    return out


def output_paths(out, blend, frame=1):
    """(png, exr) paths: --out with or without an extension (Blender's '//' and '#' read as
    blender_path does), else render/<name>; an --out that is a directory (existing, or ending
    in a separator) gets <name> inside it."""
    stem = os.path.splitext(os.path.basename(blend))[0] if blend else "demo"
    if out is not None:
        out = blender_path(out, frame, blend)
    if out is None:
        out = os.path.join("render", stem)
    elif not out or out.endswith(("/", os.sep)) or os.path.isdir(out):
        out = os.path.join(out or ".", stem)
    base, ext = os.path.splitext(out)
    if ext.lower() not in (".png", ".exr") + OTHER_IMAGE_EXTENSIONS:
        base = out                      # no image extension: the name is the base
    return base + ".png", base + ".exr"


# an --out in another image format names the base of the PNG and EXR written (shot.jpg: shot.png,
# shot.exr), rather than shot.jpg.png
OTHER_IMAGE_EXTENSIONS = (".jpg", ".jpeg", ".tif", ".tiff", ".bmp", ".webp", ".hdr", ".tga")


def save_render(scene, png, exr):
    """Write the render result as png and exr; returns the files written (a stereo or
    multiview render: one per view, Blender's view suffix before the extension, whatever
    the .blend's Output > Views Format)."""
    image = bpy.data.images['Render Result']
    r = scene.render
    settings = r.image_settings
    media = getattr(settings, 'media_type', None)
    saved = (settings.file_format, settings.color_mode, settings.color_depth)
    codec, views_format = settings.exr_codec, settings.views_format
    aspect = (r.pixel_aspect_x, r.pixel_aspect_y)
    written = []
    try:
        exr_format = 'OPEN_EXR_MULTILAYER' if _layers_or_passes(scene) else 'OPEN_EXR'
        for path, fmt, depth in ((png, 'PNG', '8'), (exr, exr_format, '32')):
            os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
            if hasattr(settings, 'media_type'):        # Blender 5: the format lists follow it
                settings.media_type = 'MULTI_LAYER_IMAGE' if fmt == 'OPEN_EXR_MULTILAYER' else 'IMAGE'
            settings.file_format = fmt
            settings.color_mode = 'RGBA'
            settings.color_depth = depth
            if fmt != 'PNG':    # lossless, whatever the .blend's output uses (DWAA: up to 7.6% off)
                settings.exr_codec = 'ZIP'
            # one file per view: Stereo 3D would make the EXR an anaglyph (R of one eye, G and
            # B of the other) or a side-by-side pair, or one multi-view file when multilayer
            settings.views_format = 'INDIVIDUAL'
            # Blender 5.0's multilayer writer gives the pixel aspect to its first part alone, and
            # OpenEXR refuses parts that disagree: with Pixel Aspect != 1 and a second part the
            # save failed (a 0-byte EXR, the render lost; Cycles' results fail alike). The pixels
            # are rendered: written at aspect 1, the aspect then set on every part
            flat = fmt == 'OPEN_EXR_MULTILAYER' and aspect != (1.0, 1.0)
            views = _view_files(scene, path)
            files = views or [path]
            for f in files:
                # a file of an earlier run must not pass for this save's (a failed write can
                # also leave it untouched)
                if os.path.isfile(f) or os.path.islink(f):
                    os.remove(f)
            if flat:
                r.pixel_aspect_x = r.pixel_aspect_y = 1.0
            failure = None
            try:
                image.save_render(filepath=os.path.abspath(path), scene=scene)
            except RuntimeError as e:
                # Blender writes each view of a multiview render to its own file and then
                # raises all the same: those files are the result, if they are images. A failed
                # write also raises, leaving them empty (0 bytes): 'wrote' had been said of those
                failure = e
            finally:
                if flat:
                    r.pixel_aspect_x, r.pixel_aspect_y = aspect
            bad = [f for f in files if not _is_image(f)]
            for f in bad:
                if os.path.isfile(f) and os.path.getsize(f) == 0:
                    os.remove(f)            # (an empty file is no partial result)
            if bad or (failure is not None and not views):     # (a single file: Blender's error is final)
                blender = str(failure).strip().splitlines()[0] if failure is not None and str(failure).strip() else ""
                raise RuntimeError(f"{' and '.join(bad or files)} not written (missing, empty or unreadable after "
                                   "the save)" + (f"; Blender: {blender}" if blender else ""))
            if flat:
                ratio = aspect[0] / aspect[1]
                for f in files:
                    why = _set_pixel_aspect(f, ratio)
                    print(f"DACRT: {f}: written at Pixel Aspect 1 (Blender 5.0 cannot write a multilayer EXR of "
                          f"several parts at {aspect[0]:g}:{aspect[1]:g}); " +
                          (f"its PixelAspectRatio is left at 1 ({why}): the pixels are the render's, to be shown "
                           f"at {ratio:g}" if why else f"its PixelAspectRatio then set to {ratio:g}"))
            written.extend(files)
    finally:
        if media is not None:
            settings.media_type = media
        settings.file_format, settings.color_mode, settings.color_depth = saved
        # after the format: a multilayer EXR had set Individual
        settings.exr_codec, settings.views_format = codec, views_format
    return written


def _is_image(path) -> bool:
    """Whether path is a non-empty file that opens as an image (OpenImageIO, where installed)."""
    if not os.path.isfile(path) or os.path.getsize(path) == 0:
        return False
    try:
        import OpenImageIO as oiio
    except ImportError:
        return True
    inp = oiio.ImageInput.open(path)
    if inp is None:
        oiio.geterror()         # (read, so OpenImageIO does not print it)
        return False
    inp.close()
    return True


def _set_pixel_aspect(path, ratio):
    """Rewrite the EXR at path with every part's PixelAspectRatio `ratio` (pixel width over
    height) and the first part's resolution as Blender writes it for that aspect; pixels,
    channels and the other attributes as they were. Returns '' when done, else why not (the
    file left as it was)."""
    try:
        import OpenImageIO as oiio
    except ImportError:
        return "OpenImageIO is not installed"
    inp = oiio.ImageInput.open(path)
    if inp is None:
        return oiio.geterror() or "it could not be read"
    parts = []
    try:
        while inp.seek_subimage(len(parts), 0):
            spec = oiio.ImageSpec(inp.spec())
            # (read as float: exact for half and float channels, written back in the spec's format)
            parts.append((spec, inp.read_image(len(parts), 0, 0, spec.nchannels, 'float')))
    finally:
        inp.close()
    if not parts or any(px is None for _, px in parts):
        return "it could not be read"
    for spec, _ in parts:
        spec.attribute('PixelAspectRatio', float(ratio))
        if 'XResolution' in [a.name for a in spec.extra_attribs]:
            # Blender's plain EXR: the wider side's density lowered by the ratio (2:1: 36 x 72)
            x, y = spec.getattribute('XResolution'), spec.getattribute('YResolution')
            spec.attribute('XResolution', float(x / max(ratio, 1.0)))
            spec.attribute('YResolution', float(y * min(ratio, 1.0)))
    fd, tmp = tempfile.mkstemp(suffix='.exr', dir=os.path.dirname(os.path.abspath(path)))
    os.close(fd)
    try:
        out = oiio.ImageOutput.create(tmp)
        ok = out is not None and out.open(tmp, [spec for spec, _ in parts])
        for i, (spec, px) in enumerate(parts if ok else ()):
            ok = ok and (i == 0 or out.open(tmp, spec, 'AppendSubimage')) and out.write_image(px)
        why = "" if ok else (out.geterror() if out is not None else oiio.geterror()) or "it could not be written"
        if out is not None:
            out.close()
        if ok:
            shutil.copymode(path, tmp)
            os.replace(tmp, path)
        return why
    finally:
        if os.path.exists(tmp):
            os.remove(tmp)


def _layers_or_passes(scene) -> bool:
    """Whether the render holds more than one view layer or any pass beyond Combined
    (engine.extra_passes): a plain EXR would keep only the first layer's Combined."""
    # every enabled layer: a headless render ignores Render Single Layer (a window's setting;
    # measured: both of two enabled layers rendered with it on)
    layers = [layer for layer in scene.view_layers if layer.use]
    if len(layers) > 1:
        return True
    # (Noisy Image, where Cycles would denoise, is Combined again: no reason for a multilayer file)
    return any(name != NOISY_IMAGE for layer in layers for name, *_ in extra_passes(layer, scene))


def _view_files(scene, path):
    """The files Blender writes for `path` per view of a multiview render (none for mono)."""
    r = scene.render
    if not r.use_multiview:
        return []
    base, ext = os.path.splitext(path)
    names = ('left', 'right') if r.views_format == 'STEREO_3D' else None
    views = [v for v in r.views if v.use and (names is None or v.name in names)]
    files = [base + v.file_suffix + ext for v in views]
    if len(set(files)) < len(files):    # one view's image would overwrite the other's, 'wrote' said of both
        same = [v.name for v, f in zip(views, files) if files.count(f) > 1]
        raise RuntimeError(f"views {', '.join(repr(n) for n in same)} share a file suffix, so their images "
                           "would be written to one file (Output Properties > Views: give each its own suffix)")
    return files


def render(args):
    if args.blend and not os.path.isfile(args.blend):
        raise SystemExit(f"error: no such .blend file: {args.blend}")
    if args.samples is not None and args.samples < 1:
        raise SystemExit("error: --samples must be at least 1")
    frames = bpy.types.Scene.bl_rna.properties['frame_current']
    if args.frame is not None and not frames.hard_min <= args.frame <= frames.hard_max:
        # (Blender's frame range: frame_set had clamped a frame past it without a word, rendering
        # another frame, or ended in a traceback beyond int32)
        raise SystemExit(f"error: --frame must be within Blender's frame range {frames.hard_min} .. {frames.hard_max}")
    try:
        register()
    except ImportError as e:          # the native module does not load: say which Python it needs
        raise SystemExit(f"error: {e}")
    if args.blend:
        try:
            bpy.ops.wm.open_mainfile(filepath=os.path.abspath(args.blend))
        except RuntimeError as e:     # not a .blend, or a damaged one
            raise SystemExit(f"error: could not open {args.blend}: {e}")
        scene = bpy.context.scene
    else:
        from .demo import build_demo_scene
        bpy.ops.wm.read_factory_settings(use_empty=True)
        scene = build_demo_scene()
    scene.render.engine = 'DACRT'
    if args.samples is not None:
        most = type(scene.dacrt).bl_rna.properties['samples'].hard_max
        if args.samples > most:          # (Blender would clamp it without a word)
            raise SystemExit(f"error: --samples must be at most {most}")
        scene.dacrt.samples = args.samples
        # every layer: a view layer's Samples override would otherwise set its count silently
        ignored = getattr(getattr(scene, 'cycles', None), 'use_layer_samples', 'USE') == 'IGNORE'
        for layer in scene.view_layers:
            if layer.use and layer.samples and not ignored:
                print(f"DACRT: --samples {args.samples} replaces view layer '{layer.name}''s "
                      f"Samples override ({layer.samples})")
                layer.samples = 0
    if args.frame is not None:
        scene.frame_set(args.frame)
    png, exr = output_paths(args.out, args.blend, scene.frame_current)
    _check_writable(png)
    if not any(layer.use for layer in scene.view_layers):
        # Blender renders nothing then, without a word, and the result cannot be saved
        raise SystemExit(f"error: scene '{scene.name}' has no view layer enabled for rendering "
                         "(View Layer Properties > Use for Rendering)")
    with _ctrl_c_cancels() as interrupted:
        try:
            bpy.ops.render.render(write_still=False, scene=scene.name)
        except RuntimeError as e:     # the engine reported an ERROR: the render failed
            if interrupted and _only_cancelled(e):    # (Ctrl-C before the frame had an image)
                print("DACRT: interrupted before the frame had an image; nothing written")
                raise SystemExit(130)
            raise SystemExit(f"error: render failed: {e}")
    try:
        written = save_render(scene, png, exr)
    except (RuntimeError, OSError) as e:     # e.g. an unwritable path: Blender's or the system's message
        raise SystemExit(f"error: could not write the image: {e}")
    if interrupted:
        done = [s.get('samples_done', 0) for s in last_render_stats().values()]
        print(f"DACRT: interrupted after {min(done, default=0)} samples; wrote the partial image to "
              f"{' and '.join(written)}")
        raise SystemExit(130)
    print(f"DACRT: wrote {' and '.join(written)}")


def _only_cancelled(error):
    """Whether every error a failed render reported is the engine's cancel before the frame had
    an image (another, such as running out of memory after the Ctrl-C, keeps its own message)."""
    lines = [line for line in str(error).splitlines() if line.strip()]
    return bool(lines) and all(engine.NOTHING_TO_WRITE in line for line in lines)


def _check_writable(path):
    """Refuse before rendering an output whose folder cannot be made or written to (the
    render would be lost after it finished)."""
    folder = os.path.dirname(os.path.abspath(path))
    try:
        os.makedirs(folder, exist_ok=True)
        with tempfile.NamedTemporaryFile(dir=folder):
            pass
    except OSError as e:
        raise SystemExit(f"error: cannot write {path}: {e.strerror or e}")


@contextlib.contextmanager
def _ctrl_c_cancels():
    """Within the block, the first SIGINT asks the engine to cancel (it stops at its next
    step and keeps the samples done; Python's KeyboardInterrupt would end the render inside
    the engine with a traceback instead); the second raises KeyboardInterrupt. Yields a list
    that is non-empty once interrupted."""
    interrupted = []

    def on_sigint(signum, frame):
        if interrupted:
            raise KeyboardInterrupt
        interrupted.append(signum)
        engine.request_cancel()
    engine.clear_cancel()
    previous = signal.signal(signal.SIGINT, on_sigint)
    try:
        yield interrupted
    finally:
        signal.signal(signal.SIGINT, previous)
        engine.clear_cancel()


def main(argv=None):
    args = parse_args(sys.argv[1:] if argv is None else argv)
    if args.command == "render":
        render(args)


if __name__ == "__main__":
    main()
