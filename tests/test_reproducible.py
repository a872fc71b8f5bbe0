"""A mission's figures must not depend on which machine runs it.

OpenBLAS, under numpy and scipy, chooses its kernels by the CPU it finds: on a Sapphire Rapids
machine it takes its SapphireRapids kernels, on another its SkylakeX or Haswell ones, and they
round differently in the last bits. The set-up's matrix inverses and pseudo-inverses and the
controller's matrix-vector products go through it, and a full-scale docking run carries those
last bits into its figures: ``tests/test_same_figures.py``'s docking RMS north error came out
1.4e-5 relative off its recorded value on a Sapphire Rapids machine (0.0247933677 against
0.0247937167 m) with the very code that had recorded it. ``scripts/setup.sh`` pins every
process of the environment to the Haswell kernels (a ``.pth`` file sets ``OPENBLAS_CORETYPE``
before numpy loads); these tests check that the pin is in force.
"""

from __future__ import annotations

import ctypes
import os
import platform
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

PINNED = "Haswell"


def _runs_haswell_kernels() -> bool:
    """x86-64 Linux with AVX2 and FMA: the machines the pin applies to."""
    if platform.machine() != "x86_64" or not Path("/proc/cpuinfo").is_file():
        return False
    flags = Path("/proc/cpuinfo").read_text()
    return all(f" {flag} " in flags for flag in ("avx2", "fma"))


def _corename(package_dir: Path, pattern: str, symbol: str) -> str:
    """The kernel family the OpenBLAS bundled in ``package_dir`` chose in this process."""
    libs = sorted(package_dir.parent.glob(f"{package_dir.name}.libs/{pattern}"))
    assert libs, f"no OpenBLAS matching {pattern} beside {package_dir}"
    lib = ctypes.CDLL(str(libs[0]))  # already loaded by the import: the same library
    get = getattr(lib, symbol)
    get.restype = ctypes.c_char_p
    return get().decode()


pytestmark = pytest.mark.skipif(
    not _runs_haswell_kernels(), reason="the OpenBLAS pin applies to x86-64 with AVX2 and FMA"
)


def test_numpy_and_scipy_run_the_pinned_openblas_kernels() -> None:
    import scipy.linalg  # loads scipy's own OpenBLAS

    numpy_core = _corename(
        Path(np.__file__).parent, "libscipy_openblas64_*.so", "scipy_openblas_get_corename64_"
    )
    scipy_core = _corename(
        Path(scipy.__file__).parent, "libscipy_openblas-*.so", "scipy_openblas_get_corename"
    )
    assert (numpy_core, scipy_core) == (PINNED, PINNED), (
        f"OpenBLAS kernels numpy {numpy_core}, scipy {scipy_core}: want {PINNED} "
        f"(OPENBLAS_CORETYPE={os.environ.get('OPENBLAS_CORETYPE')!r}; scripts/setup.sh writes "
        "the .pth file that sets it)"
    )


def test_a_new_process_of_the_environment_is_pinned_too() -> None:
    """Every process started with the environment's Python (campaign workers, the console,
    the command line), not only this one: the pin comes from the environment's ``.pth``."""
    env = {k: v for k, v in os.environ.items() if k != "OPENBLAS_CORETYPE"}
    out = subprocess.run(
        [sys.executable, "-c", "import os; print(os.environ.get('OPENBLAS_CORETYPE'))"],
        env=env,
        capture_output=True,
        text=True,
        check=True,
    )
    assert out.stdout.strip() == PINNED
