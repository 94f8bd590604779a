#!/usr/bin/env python3
"""Project driver: sets up .venv, builds the native tracer and runs tests, renders, benchmarks
and packaging.

    python3 build.py test [--stress] [--precise] [--sanitize] [pytest args...]
    python3 build.py render [scene.blend] [--samples N] [--out file]
    python3 build.py bench [tracer|errortime|scaling|animation|partition|...] [options]
    python3 build.py compare scene.blend [--samples N]
    python3 build.py package

Every command first checks the machine's prerequisites, creates `.venv` at the repository root
when it is missing, installs `requirements.txt` into it when that file changed since the last
install, and (re)builds the native package `dacrt` from `native/` when its sources changed.
Standard library only, so it runs under the system python3 before any venv exists.
Long logs go to build/logs/; their path is printed when a step fails.
"""

import ctypes.util
import fcntl
import hashlib
import os
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path
from typing import Dict, List, Optional

ROOT = Path(__file__).resolve().parent
VENV = ROOT / ".venv"
VPY = VENV / "bin" / "python"
BUILD = ROOT / "build"
LOGS = BUILD / "logs"
NATIVE = ROOT / "native"
REQUIREMENTS = ROOT / "requirements.txt"
REQ_STAMP = VENV / ".dacrt-requirements.sha256"
NATIVE_STAMP = VENV / ".dacrt-native.sha256"

PYTHON_NEEDED = (3, 11)  # bpy 5.0.1 is built for CPython 3.11 only
PY = "%d.%d" % PYTHON_NEEDED

# Shared libraries the bpy 5.0.1 wheel loads from the system (found with ldd on its .so files and
# by reading /proc/self/maps after `import bpy` and a Cycles render): soname -> Debian package.
# libXxf86vm and libEGL, needed by older Blender builds, are not loaded by 5.0.1.
BPY_SYSTEM_LIBS = {
    "libX11.so.6": "libx11-6",
    "libXext.so.6": "libxext6",
    "libXrender.so.1": "libxrender1",
    "libXfixes.so.3": "libxfixes3",
    "libXi.so.6": "libxi6",
    "libxkbcommon.so.0": "libxkbcommon0",
    "libSM.so.6": "libsm6",
    "libICE.so.6": "libice6",
    "libGL.so.1": "libgl1",
    "libGLX.so.0": "libglx0",
    "libGLdispatch.so.0": "libglvnd0",
}

# Directories inside native/ that hold build output, not sources (excluded from its hash).
NATIVE_NON_SOURCE = {"build", "dist", "_skbuild", "__pycache__", ".git", ".pytest_cache"}


class SetupError(Exception):
    """A prerequisite or build step failed; the message says what to do."""


def say(msg: str) -> None:
    print(f"[build.py] {msg}", flush=True)


def run_logged(cmd: List[str], log_name: str, what: str, env: Optional[dict] = None) -> None:
    """Run a noisy command with its output in build/logs/<log_name>; on failure show the tail."""
    LOGS.mkdir(parents=True, exist_ok=True)
    log = LOGS / log_name
    with open(log, "w") as f:
        f.write("$ " + " ".join(cmd) + "\n\n")
        f.flush()
        rc = subprocess.call(cmd, stdout=f, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
                             cwd=ROOT, env=env or quiet_env())
    if rc != 0:
        tail = log.read_text(errors="replace").splitlines()[-25:]
        raise SetupError(f"{what} failed (exit {rc}). Last lines of the log:\n    "
                         + "\n    ".join(tail) + f"\nFull log: {log}")


def quiet_env() -> dict:
    return dict(os.environ, PIP_DISABLE_PIP_VERSION_CHECK="1", PIP_NO_INPUT="1")


# ---------------------------------------------------------------------------------------------
# Prerequisites


def find_library(soname: str, ldconfig_text: str) -> bool:
    if re.search(r"^\s*" + re.escape(soname) + r"\s", ldconfig_text, re.M):
        return True
    stem = soname[3:].split(".so")[0]  # libX11.so.6 -> X11
    found = ctypes.util.find_library(stem)
    return found is not None and found.startswith(soname.split(".so")[0] + ".so")


def check_prerequisites() -> None:
    """Collect every missing prerequisite, then fail once with the exact fix for each."""
    problems: List[str] = []
    apt: List[str] = []

    if sys.version_info[:2] != PYTHON_NEEDED:
        problems.append(
            f"Python {PY} is required (bpy 5.0.1 exists only for it); this is "
            f"{sys.version.split()[0]} at {sys.executable}, and no python{PY} is on PATH.")
        apt += [f"python{PY}", f"python{PY}-venv", f"python{PY}-dev"]
    else:
        if not VPY.exists():
            try:
                import ensurepip  # noqa: F401  (Debian splits it out into python3.X-venv)
            except ImportError:
                problems.append("the Python venv module cannot bootstrap pip (ensurepip missing).")
                apt.append(f"python{PY}-venv")
        import sysconfig
        include = Path(sysconfig.get_paths()["include"]) / "Python.h"
        if not include.exists():
            problems.append(f"Python development headers are missing ({include}), "
                            "needed to compile the native module.")
            apt.append(f"python{PY}-dev")

    if not (shutil.which("c++") or shutil.which("g++")):
        problems.append("no C++ compiler (`c++` or `g++`) on PATH.")
        apt.append("g++")

    try:
        ldconfig = subprocess.run(["ldconfig", "-p"], stdout=subprocess.PIPE,
                                  stderr=subprocess.DEVNULL, stdin=subprocess.DEVNULL,
                                  universal_newlines=True).stdout
    except OSError:
        ldconfig = ""
    missing = [so for so in BPY_SYSTEM_LIBS if not find_library(so, ldconfig)]
    if missing:
        problems.append("system libraries that bpy (Blender as a Python module) loads are missing: "
                        + ", ".join(missing) + ".")
        apt += [BPY_SYSTEM_LIBS[so] for so in missing]

    if problems:
        msg = "Missing prerequisites:\n  - " + "\n  - ".join(problems)
        if apt:
            msg += ("\nInstall them with (as root, Debian/Ubuntu):\n    apt-get install -y "
                    + " ".join(dict.fromkeys(apt)))
        raise SetupError(msg)


# ---------------------------------------------------------------------------------------------
# Virtual environment, dependencies, native build


def venv_python_version() -> str:
    out = subprocess.run([str(VPY), "-c", "import sys; print('%d.%d.%d' % sys.version_info[:3])"],
                         capture_output=True, text=True, stdin=subprocess.DEVNULL)
    if out.returncode != 0:
        raise SetupError(f"{VPY} does not run ({out.stderr.strip()[-300:]}). "
                         f"Delete {VENV} and rerun to recreate it.")
    return out.stdout.strip()


def ensure_venv() -> None:
    if not VPY.exists():
        say(f"creating {VENV.relative_to(ROOT)} with {sys.executable}")
        run_logged([sys.executable, "-m", "venv", str(VENV)], "venv.log", "creating .venv")
    version = venv_python_version()
    if tuple(int(x) for x in version.split(".")[:2]) != PYTHON_NEEDED:
        raise SetupError(f"{VENV} runs Python {version}, but {PY} is required (bpy 5.0.1). "
                         f"Delete {VENV} and rerun.")


def requirements_hash() -> str:
    if not REQUIREMENTS.exists():
        raise SetupError(f"{REQUIREMENTS} is missing.")
    h = hashlib.sha256(REQUIREMENTS.read_bytes())
    h.update(venv_python_version().encode())
    return h.hexdigest()


def ensure_requirements() -> str:
    digest = requirements_hash()
    if REQ_STAMP.exists() and REQ_STAMP.read_text().strip() == digest:
        return digest
    say("installing pinned dependencies from requirements.txt (first run downloads ~0.5 GB) ...")
    t0 = time.time()
    # --no-deps: requirements.txt is a complete lock (see its header for why).
    run_logged([str(VPY), "-m", "pip", "install", "--no-deps", "-r", str(REQUIREMENTS)],
               "pip.log", "installing requirements.txt")
    REQ_STAMP.write_text(digest + "\n")
    say(f"dependencies installed ({time.time() - t0:.0f} s)")
    return digest


def native_sources_hash(extra: str) -> str:
    if not (NATIVE / "pyproject.toml").exists():
        raise SetupError(f"{NATIVE}/pyproject.toml is missing: the native tracer package is not "
                         "in this tree yet, so there is nothing to build.")
    h = hashlib.sha256(extra.encode())
    for dirpath, dirnames, filenames in os.walk(NATIVE):
        dirnames[:] = sorted(d for d in dirnames
                             if d not in NATIVE_NON_SOURCE and not d.endswith(".egg-info"))
        for name in sorted(filenames):
            if name.endswith((".pyc", ".so", ".o")):
                continue
            path = Path(dirpath) / name
            h.update(str(path.relative_to(NATIVE)).encode() + b"\0")
            h.update(path.read_bytes() + b"\0")
    return h.hexdigest()


def dacrt_installed() -> bool:
    code = "import importlib.util, sys; sys.exit(importlib.util.find_spec('dacrt') is None)"
    return subprocess.call([str(VPY), "-c", code], stdin=subprocess.DEVNULL) == 0


def native_config_settings(build_dir: Path, defines: Dict[str, str]) -> List[str]:
    # A persistent CMake build dir makes rebuilds incremental (scikit-build-core `build-dir`).
    args = [f"--config-settings=build-dir={build_dir}"]
    args += [f"--config-settings=cmake.define.{k}={v}" for k, v in defines.items()]
    return args


def ensure_native(req_digest: str) -> None:
    digest = native_sources_hash("release|" + req_digest)
    if NATIVE_STAMP.exists() and NATIVE_STAMP.read_text().strip() == digest and dacrt_installed():
        return
    say("building the native tracer (native/ changed) ...")
    t0 = time.time()
    run_logged([str(VPY), "-m", "pip", "install", "--no-deps", "--no-build-isolation",
                "--force-reinstall", *native_config_settings(BUILD / "native", {}), str(NATIVE)],
               "native.log", "building native/ (pip install ./native)")
    NATIVE_STAMP.write_text(digest + "\n")
    say(f"native tracer built and installed ({time.time() - t0:.0f} s)")


class SetupLock:
    """Serialises the set-up of concurrent build.py runs in one tree (several people share it):
    pip into the same .venv or CMake in the same build dir at once would corrupt them."""

    def __enter__(self):
        BUILD.mkdir(exist_ok=True)
        self.fh = open(BUILD / ".setup.lock", "w")
        try:
            fcntl.flock(self.fh, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            say("another build.py is setting up this tree; waiting for it ...")
            fcntl.flock(self.fh, fcntl.LOCK_EX)
        return self

    def __exit__(self, *exc):
        fcntl.flock(self.fh, fcntl.LOCK_UN)
        self.fh.close()


def setup(build_native: bool = True) -> str:
    """Prerequisites, .venv, requirements and (optionally) the native build; call it holding
    SetupLock. Returns the requirements hash (part of the native builds' stamps)."""
    check_prerequisites()
    ensure_venv()
    req = ensure_requirements()
    if build_native:
        ensure_native(req)
    return req


# ---------------------------------------------------------------------------------------------
# Sanitizer build (ASan + UBSan) into build/sanitize/, used only by `test --sanitize`

SAN_DIR = BUILD / "sanitize"
SAN_SITE = SAN_DIR / "site"


def sanitizer_preload() -> str:
    """LD_PRELOAD value for running the uninstrumented Python with the sanitized module: the
    ASan runtime first, and libstdc++ with it, or ASan cannot intercept C++ exceptions
    (`CHECK failed ... real___cxa_throw`) when the module raises ValueError."""
    cxx = shutil.which("c++") or shutil.which("g++")
    paths = []
    for lib in ("libasan.so", "libstdc++.so.6"):
        path = subprocess.run([cxx, f"-print-file-name={lib}"], capture_output=True, text=True,
                              stdin=subprocess.DEVNULL).stdout.strip()
        if not os.path.isabs(path) or not os.path.exists(path):
            raise SetupError(f"{lib} was not found for {cxx}. Install it with:\n"
                             "    apt-get install -y libasan8 libubsan1 libstdc++6   (as root)")
        paths.append(os.path.realpath(path))
    return " ".join(paths)


def build_native_variant(root: Path, option: str, label: str, digest: str, check=None) -> Path:
    """Build dacrt with the CMake option `option`=ON into root/site (CMake tree root/cmake)
    unless root/stamp.sha256 already holds `digest`; check(site) may refuse the result with a
    SetupError before the stamp is written. Returns root/site."""
    site, stamp = root / "site", root / "stamp.sha256"
    if not (stamp.exists() and stamp.read_text().strip() == digest):
        say(f"building the {label} native tracer ({option}=ON) ...")
        t0 = time.time()
        run_logged([str(VPY), "-m", "pip", "install", "--no-deps", "--no-build-isolation",
                    "--upgrade", "--target", str(site),
                    *native_config_settings(root / "cmake", {option: "ON"}), str(NATIVE)],
                   f"native-{root.name}.log", f"building native/ with {option}=ON")
        if check is not None:
            check(site)
        stamp.write_text(digest + "\n")
        say(f"{label} build done ({time.time() - t0:.0f} s)")
    return site


def _check_links_asan(site: Path) -> None:
    modules = [p for p in site.rglob("*.so")]
    linked = any("libasan" in subprocess.run(["ldd", str(p)], capture_output=True,
                                             text=True).stdout for p in modules)
    if not linked:
        raise SetupError("native/ was built with -C cmake.define.DACRT_SANITIZE=ON but the "
                         f"module in {site} does not link libasan: native/CMakeLists.txt "
                         "does not implement the DACRT_SANITIZE option yet.")


def ensure_sanitized_native(req_digest: str) -> dict:
    """Build dacrt with -fsanitize=address,undefined (CMake option DACRT_SANITIZE=ON) into
    build/sanitize/site and return the environment that runs Python with it."""
    preload = sanitizer_preload()
    build_native_variant(SAN_DIR, "DACRT_SANITIZE", "sanitized (ASan+UBSan)",
                         native_sources_hash("sanitize|" + req_digest), _check_links_asan)
    env = dict(os.environ)
    env["PYTHONPATH"] = str(SAN_SITE) + (os.pathsep + env["PYTHONPATH"]
                                         if env.get("PYTHONPATH") else "")
    env["LD_PRELOAD"] = preload  # the Python executable itself is not instrumented
    # CPython leaks by design at exit; UB must fail the run instead of just printing.
    env["ASAN_OPTIONS"] = "detect_leaks=0:abort_on_error=1"
    env["UBSAN_OPTIONS"] = "halt_on_error=1:abort_on_error=1:print_stacktrace=1"
    probe = subprocess.run([str(VPY), "-c", "import dacrt; print(dacrt.__file__)"], env=env,
                           capture_output=True, text=True, stdin=subprocess.DEVNULL, cwd=ROOT)
    if probe.returncode != 0 or str(SAN_SITE) not in probe.stdout:
        raise SetupError("the sanitized dacrt does not import from "
                         f"{SAN_SITE}:\n{probe.stdout}{probe.stderr[-2000:]}")
    return env


# Non-robust build (CMake option DACRT_NONROBUST=ON: no box padding, no double-precision lanes)
# into build/nonrobust/site, used only by `bench robustness` to measure what robustness costs.
NONROBUST_DIR = BUILD / "nonrobust"


def ensure_nonrobust_native() -> Path:
    """Build dacrt with DACRT_NONROBUST=ON into build/nonrobust/site when native/ changed;
    returns that directory (it holds a `dacrt` package). Call it holding SetupLock, after
    setup()."""
    return build_native_variant(NONROBUST_DIR, "DACRT_NONROBUST", "non-robust",
                                native_sources_hash("nonrobust|" + requirements_hash()))


# ---------------------------------------------------------------------------------------------
# Commands


def cmd_test(args: List[str]) -> int:
    stress = "--stress" in args
    sanitize = "--sanitize" in args
    rest = [a for a in args if a not in ("--stress", "--sanitize")]
    env = None
    paths = ["tests"]
    with SetupLock():
        req = setup()
        if sanitize:
            env = ensure_sanitized_native(req)
            # the tracer tests and the cheap (default) stress tests, not the renderer ones
            paths = ["tests/native", "tests/stress", "--ignore=tests/stress/test_renderer.py"]
    named = any(not a.startswith("-") and (ROOT / a.split("::")[0]).exists() for a in rest)
    if named:
        paths = []  # the caller named what to run
    # A whole tier runs on every core (pytest-xdist, one worker process per core; work is
    # stolen between them, so a long parity file does not hold one worker): most tests are
    # single-threaded Python and bpy. Named tests, or a -n of the caller's, run as asked.
    workers = [] if named or sanitize or any(a.startswith(("-n", "--numprocesses")) for a in rest) \
        else ["-n", "auto", "--dist", "worksteal"]
    # Stress tests are deselected by tests/conftest.py unless --stress is given.
    cmd = [str(VPY), "-m", "pytest", f"--rootdir={ROOT}", *(["--stress"] if stress else []),
           *workers, *paths, *rest]
    say("running: " + " ".join(cmd[1:]) + (" (sanitized build)" if sanitize else ""))
    return subprocess.call(cmd, cwd=ROOT, env=env)


def run_module(module: str, module_path: Path, args: List[str], owner: str) -> int:
    if not module_path.exists():
        raise SetupError(f"{module_path.relative_to(ROOT)} does not exist yet ({owner}); "
                         f"`python -m {module}` has nothing to run.")
    # run where the user is, so relative paths (a scene, --out) mean what they typed; the
    # repository root goes on the import path for `-m` instead of being the working directory
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(p for p in (str(ROOT), env.get("PYTHONPATH", "")) if p)
    return subprocess.call([str(VPY), "-m", module, *args], env=env)


def cmd_render(args: List[str]) -> int:
    with SetupLock():
        setup()
    return run_module("addon.cli", ROOT / "addon" / "cli.py", ["render", *args],
                      "the add-on's command-line entry point")


def cmd_bench(args: List[str]) -> int:
    with SetupLock():
        setup()
    bench = ROOT / "tests" / "bench"
    if not (bench / "__main__.py").exists():
        raise SetupError("tests/bench/__main__.py does not exist yet (the benchmark package); "
                         "`python -m tests.bench` has nothing to run.")
    return run_module("tests.bench", bench, args, "the benchmark package")


def cmd_compare(args: List[str]) -> int:
    if not args or args[0].startswith("-"):
        raise SetupError("usage: python3 build.py compare scene.blend [--samples N] "
                         "(or a built-in scene: cornell, outdoor, dragon, environment)")
    return cmd_bench(["compare", *args])


def set_manifest_wheels(text: str, wheels: List[str]) -> str:
    """Return manifest text whose top-level `wheels` key lists exactly `wheels`."""
    line = "wheels = [" + ", ".join(f'"{w}"' for w in wheels) + "]\n"
    m = re.search(r"^wheels\s*=\s*\[.*?\][^\n]*\n?", text, re.M | re.S)
    if m:
        return text[:m.start()] + line + text[m.end():]
    t = re.search(r"^\s*\[", text, re.M)  # top-level keys must come before the first table
    pos = t.start() if t else len(text)
    if pos and not text[:pos].endswith("\n"):
        line = "\n" + line
    return text[:pos] + line + text[pos:]


def cmd_package(args: List[str]) -> int:
    if args:
        raise SetupError(f"`package` takes no arguments (got {' '.join(args)}).")
    manifest = ROOT / "addon" / "blender_manifest.toml"
    if not manifest.exists():
        raise SetupError("addon/blender_manifest.toml does not exist yet: it describes the Blender "
                         "extension (id, version, ...) and is written with the add-on. "
                         "Nothing to package without it.")
    native_sources_hash("")  # fails clearly when native/ is not there
    stage_root = BUILD / "package"
    stage = stage_root / "addon"
    wheels_dir = stage / "wheels"
    with SetupLock():
        setup(build_native=False)
        if stage_root.exists():
            shutil.rmtree(stage_root)
        wheels_dir.mkdir(parents=True)
        say("building the native wheel ...")
        run_logged([str(VPY), "-m", "pip", "wheel", "--no-deps", "--no-build-isolation",
                    *native_config_settings(BUILD / "native", {}), "-w", str(wheels_dir),
                    str(NATIVE)],
                   "package-wheel.log", "pip wheel ./native")
    wheels = sorted(p.name for p in wheels_dir.glob("*.whl"))
    if not wheels:
        raise SetupError(f"pip wheel produced no .whl in {wheels_dir}.")

    shutil.copytree(ROOT / "addon", stage, dirs_exist_ok=True,
                    ignore=shutil.ignore_patterns("__pycache__", "*.pyc", "tests"))
    text = set_manifest_wheels(manifest.read_text(), [f"./wheels/{w}" for w in wheels])
    (stage / "blender_manifest.toml").write_text(text)
    import tomllib  # here, not at the top: build.py must start on other Pythons to say so
    try:
        tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise SetupError(f"the staged manifest is not valid TOML ({e}); source: {manifest}")

    found = sorted((VENV / "lib").glob(
        "python3.*/site-packages/bpy/*/scripts/addons_core/bl_pkg/cli/blender_ext.py"))
    if not found:
        raise SetupError("blender_ext.py (Blender's extension builder) was not found inside the "
                         "installed bpy package in .venv.")
    dist = ROOT / "dist"
    dist.mkdir(exist_ok=True)
    say("building the extension zip with Blender's blender_ext.py ...")
    run_logged([str(VPY), str(found[0]), "build", "--source-dir", str(stage),
                "--output-dir", str(dist)], "package-extension.log", "blender_ext.py build")
    log = (LOGS / "package-extension.log").read_text()
    zips = re.findall(r"created: \"?([^\"\n]+\.zip)", log)
    if not zips:
        raise SetupError(f"blender_ext.py reported no zip; see {LOGS / 'package-extension.log'}")
    say(f"staged in {stage.relative_to(ROOT)}; wheel(s): {', '.join(wheels)}")
    say(f"extension: {zips[-1]}")
    return 0


COMMANDS = {"test": cmd_test, "render": cmd_render, "bench": cmd_bench, "compare": cmd_compare,
            "package": cmd_package}


def use_python_311(argv: List[str]) -> None:
    """Re-run this script under python3.11 when started by another Python and one is on PATH."""
    if sys.version_info[:2] == PYTHON_NEEDED or os.environ.get("DACRT_BUILD_REEXEC"):
        return
    other = shutil.which(f"python{PY}")
    if other:
        say(f"this is Python {sys.version.split()[0]}; bpy 5.0.1 needs {PY}: re-running with {other}")
        os.environ["DACRT_BUILD_REEXEC"] = "1"
        sys.stdout.flush()
        os.execv(other, [other, str(Path(__file__).resolve()), *argv])


def main(argv: List[str]) -> int:
    if not argv or argv[0] in ("-h", "--help", "help") or argv[0] not in COMMANDS:
        print(__doc__.strip())
        if argv and argv[0] not in ("-h", "--help", "help"):
            print(f"\nunknown command: {argv[0]}")
            return 2
        return 0 if argv else 2
    use_python_311(argv)
    try:
        return COMMANDS[argv[0]](argv[1:])
    except SetupError as e:
        print(f"[build.py] ERROR: {e}", file=sys.stderr, flush=True)
        return 2
    except KeyboardInterrupt:
        return 130


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
