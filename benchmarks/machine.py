"""Which machine a benchmark ran on: the processor, the instruction set numba compiles the
kernels for, and the cores. Speed figures mean little without it: the same code runs at
different speeds on processors of different generations and vector widths."""

from __future__ import annotations

import os
import platform
from pathlib import Path
from typing import Any


def cpu_model(cpuinfo: Path = Path("/proc/cpuinfo")) -> str:
    """The processor's model name as the kernel reports it (``platform.processor()`` where
    there is no /proc/cpuinfo)."""
    try:
        for line in cpuinfo.read_text().splitlines():
            key, _, value = line.partition(":")
            if key.strip() == "model name" and value.strip():
                return value.strip()
    except OSError:
        pass
    return platform.processor() or platform.machine() or "unknown"


def simd_of(features: dict[str, bool]) -> str:
    """The widest vector instruction set among LLVM's host features: what numba's compiled
    loops over the runs of a batch can use."""
    if features.get("avx512f"):
        return "AVX-512"
    if features.get("avx2"):
        return "AVX2"
    if features.get("avx"):
        return "AVX"
    if features.get("neon") or features.get("sve"):
        return "NEON/SVE"
    return "SSE or none"


def describe() -> dict[str, Any]:
    """{"cpu", "llvm_cpu", "simd", "cores"} of this machine."""
    from llvmlite import binding

    features = {name: bool(on) for name, on in binding.get_host_cpu_features().items()}
    return {
        "cpu": cpu_model(),
        "llvm_cpu": str(binding.get_host_cpu_name()),
        "simd": simd_of(features),
        "cores": os.cpu_count() or 1,
    }


def text(machine: dict[str, Any]) -> str:
    """One line for a report: 'AMD EPYC (znver3, AVX2, 2 cores)'."""
    return f"{machine['cpu']} ({machine['llvm_cpu']}, {machine['simd']}, {machine['cores']} cores)"
