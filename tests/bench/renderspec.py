"""What a rendering benchmark renders: a scene (built-in or a .blend) and the settings both
engines share. Plain data, no Blender: the benchmark's parent process builds these and the bpy
worker (renderworker.py) turns them into scenes (renderscenes.py).

Built-in scenes and their settings (160x120 is the issue's Cornell-box size):
    cornell  4 bounces, Blackman-Harris 1.5     outdoor  3 bounces, Gaussian 1.5
    dragon   3 bounces, Blackman-Harris 1.5     environment  3 bounces, Blackman-Harris 1.5
    many_lights  3 bounces, Blackman-Harris 1.5 (a street of 12 lamps, emissive globes, a sun)
"""

from __future__ import annotations

import hashlib
import json
import os
from dataclasses import asdict, dataclass, field
from importlib import metadata
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]


@dataclass
class RenderSpec:
    name: str
    resolution: tuple = (160, 120)
    bounces: int | None = 4           # None: a .blend's own Cycles diffuse bounce count
    filter_type: str | None = 'BLACKMAN_HARRIS'   # None: a .blend's own Cycles pixel filter
    filter_width: float = 1.5
    blend: str | None = None          # a .blend file instead of a built-in builder
    grid: int = 0                     # the animation benchmark's wave grid: quads per side
    # a .blend's materials: 'diffuse' = made what DACRT renders exactly, for both engines
    # (fairmaterials.py, reference section 2.7), or 'as-is' (Cycles renders them in full)
    materials: str = 'diffuse'
    extra: dict = field(default_factory=dict)

    def as_dict(self) -> dict:
        d = asdict(self)
        d["resolution"] = list(self.resolution)
        return d


BUILTIN = {
    "cornell": dict(resolution=(160, 120), bounces=4),
    "outdoor": dict(resolution=(160, 120), bounces=3, filter_type='GAUSSIAN'),
    "dragon": dict(resolution=(160, 120), bounces=3),
    "environment": dict(resolution=(160, 120), bounces=3),
    "many_lights": dict(resolution=(160, 120), bounces=3),
}


def builtin_spec(name: str, resolution=None, bounces=None) -> RenderSpec:
    if name not in BUILTIN:
        raise ValueError(f"unknown built-in scene {name!r} (have {', '.join(BUILTIN)})")
    kw = dict(BUILTIN[name])
    if resolution is not None:
        kw["resolution"] = tuple(resolution)
    if bounces is not None:
        kw["bounces"] = bounces
    return RenderSpec(name=name, **kw)


MATERIAL_MODES = ('diffuse', 'as-is')


def blend_spec(path: str, bounces: int | None = None, materials: str = 'diffuse') -> RenderSpec:
    """A .blend file at its own resolution; bounces and pixel filter from its Cycles settings
    (read when the worker opens it) unless bounces is given; materials: see RenderSpec."""
    if materials not in MATERIAL_MODES:
        raise ValueError(f"materials must be one of {', '.join(MATERIAL_MODES)}, got {materials!r}")
    if not path.endswith(".blend"):
        raise ValueError(f"{path}: scenes given by path must be .blend files")
    if not os.path.isfile(path):
        raise ValueError(f"no such .blend file: {path}")
    name = os.path.splitext(os.path.basename(path))[0]
    return RenderSpec(name=name, blend=os.path.abspath(path), bounces=bounces, filter_type=None,
                      resolution=(0, 0), materials=materials)


def scene_spec(arg: str, bounces: int | None = None, materials: str = 'diffuse') -> RenderSpec:
    """A command-line scene: a built-in name (diffuse already) or a .blend path."""
    if arg in BUILTIN:
        return builtin_spec(arg, bounces=bounces)
    return blend_spec(arg, bounces, materials)


def _bpy_version() -> str:
    try:
        return metadata.version("bpy")
    except metadata.PackageNotFoundError:
        return "unknown"


def source_text(spec: RenderSpec) -> str:
    """What the scene's pixels depend on besides the settings: the builders' sources (read as
    text: no Blender needed) or, for a file, its path, size and mtime."""
    if spec.blend:
        st = os.stat(spec.blend)
        text = f"blend:{spec.blend}:{st.st_size}:{int(st.st_mtime)}"
        if spec.materials == 'diffuse':     # the override decides what Cycles renders
            text += "\n" + (REPO / "tests/bench/fairmaterials.py").read_text()
        return text
    files = ["tests/parity/scenes.py", "tests/parity/rendering.py",
             "tests/bench/renderscenes.py", "tests/bench/renderworker.py"]
    text = "\n".join((REPO / f).read_text() for f in files)
    if spec.name == "dragon":
        from .scenes import REAL, SHARED_SCENES
        text += f"\ndragon file present: {(SHARED_SCENES / REAL['dragon'][0]).exists()}"
    return text


def reference_key(spec: RenderSpec, samples: int, seeds: list[int]) -> str:
    """Cache key of a Cycles reference: scene source, settings, seeds, bpy version."""
    desc = dict(spec=spec.as_dict(), samples=samples, seeds=list(seeds),
                source=hashlib.sha256(source_text(spec).encode()).hexdigest(),
                bpy=_bpy_version())
    return hashlib.sha256(json.dumps(desc, sort_keys=True).encode()).hexdigest()[:16]
