"""Running a kernel once per instruction set: DACRT_ISA picks the kernel copy once per process,
so each instruction set's outputs come from a fresh process (the per-ISA bit-equality tests)."""
import os
import subprocess
import sys
import tempfile

import dacrt
import numpy as np

_ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def outputs_per_isa(script, *arrays):
    """{isa: the array script saved} for every instruction set this machine runs. script reads
    its inputs from the .npy files sys.argv[1:-1] (arrays, in order) and saves one array to
    sys.argv[-1]; it runs from the repository root with this process's import path."""
    out = {}
    with tempfile.TemporaryDirectory() as tmp:
        names = []
        for k, a in enumerate(arrays):
            names.append(os.path.join(tmp, f'in{k}.npy'))
            np.save(names[-1], a)
        for isa in dacrt.supported_isas():
            path = os.path.join(tmp, f'{isa}.npy')
            subprocess.run([sys.executable, '-c', script, *names, path], check=True, cwd=_ROOT,
                           env={**os.environ, 'DACRT_ISA': isa,
                                'PYTHONPATH': os.pathsep.join([_ROOT] + sys.path)})
            out[isa] = np.load(path)
    return out
