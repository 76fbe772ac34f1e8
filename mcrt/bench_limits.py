"""How far mcrt's path kernel is from the machine: its instructions, vector width and memory traffic per path segment.

Measured, not modelled:

- segments and shadow rays per path: the path kernel run once with a host
  that counts the closest-hit and shadow rays it is asked for (a scatter-add
  per call, so that run is not timed);
- the kernel's time: Dr.Jit's kernel history over repeated launches of the
  ordinary (frozen) kernel, and the process's CPU time over them;
- its machine code: the kernel compiled cold (an empty Dr.Jit cache, in a
  child process) with Dr.Jit's trace log on, which disassembles every kernel
  it compiles; the path loop is the widest backward branch inside the
  packet loop, and its instructions are counted statically (vector ones,
  those on zmm registers, and stack accesses);
- the machine's memory bandwidth: a NumPy copy of 256 MiB.

Without hardware counters (``perf stat`` on this kind of virtual machine
reports cycles and instructions as not supported) the dynamic instruction
count is not measured; the report gives the static loop body against the
cycles each packet iteration took.
"""

from __future__ import annotations

import json
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

_DISASM = re.compile(r"jit_llvm_disasm\(\): (0x[0-9a-f]+)\s+(\S+)\s*(.*)$")

_COMPILE_SCRIPT = """
import sys
import mcrt
import drjit as dr
from mcrt.scene import load_scene
from mcrt.tracer import Tracer, lane_layout, pixel_range
camera, res, spp, depth = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4])
t = Tracer(load_scene(), camera, res, res, depth)
k, b = lane_layout(res * res, spp)
dr.set_log_level(dr.LogLevel.Trace)
t.launch(1, None, pixel_range(t.m, 0, res * res), 0, min(spp, k * b), k, b)
dr.sync_thread()
dr.set_log_level(dr.LogLevel.Warn)
"""


class _CountingHost:
    """A host that counts the rays the estimator asks for: slot 0 closest hits, slot 1 shadow rays."""

    def __init__(self, host, counter):
        self._host, self._counter = host, counter

    def __getattr__(self, name):
        return getattr(self._host, name)

    def _count(self, slot: int, active) -> None:
        import drjit as dr

        m = self._host.m
        dr.scatter_reduce(dr.ReduceOp.Add, self._counter, m.UInt32(1), m.UInt32(slot), m.Bool(active),
                          mode=dr.ReduceMode.Local)

    def intersect(self, o, d, active=True):
        self._count(0, active)
        return self._host.intersect(o, d, active)

    def occluded(self, o, d, tmax, active=True):
        self._count(1, active)
        return self._host.occluded(o, d, tmax, active)


def ray_counts(scene, *, camera: str, res: int, spp: int, max_depth: int, backend: str = "llvm") -> dict:
    """Closest-hit segments and shadow rays per path, counted in one launch of res x res x spp paths."""
    import drjit as dr

    from mcrt.estimator import PathEstimator
    from mcrt.tracer import Tracer, lane_layout, pixel_range, stream_keys

    tracer = Tracer(scene, camera, res, res, max_depth, backend=backend)
    m = tracer.m
    counter = dr.zeros(m.UInt32, 2)
    tracer.estimator = PathEstimator(_CountingHost(tracer.estimator.host, counter), tracer.options)
    k, b = lane_layout(res * res, spp)
    n = min(spp, k * b)
    zeros = dr.zeros(m.Float64, res * res)
    params = m.UInt32([*stream_keys(1), 0, n, 0])
    dr.eval(tracer._launch_kernel(((zeros,) * 3, (zeros,) * 3), pixel_range(m, 0, res * res), params, k, b, res * res))
    segments, shadow = (int(v) for v in counter.numpy())
    paths = res * res * n
    return {"paths": paths, "segments": segments, "shadow_rays": shadow, "segments_per_path": segments / paths,
            "shadow_rays_per_path": shadow / paths, "lanes_per_pixel": k, "paths_per_lane": b}


def kernel_seconds(scene, *, camera: str, res: int, spp: int, max_depth: int, backend: str = "llvm",
                   repeats: int = 5) -> tuple[float, float]:
    """(median execution time of the path kernel, median process CPU time of a launch), after one warm-up launch.

    The kernel time is the longest kernel of a launch (Dr.Jit's kernel
    history); the CPU time that of every thread of this process over the
    launch, which a machine shared with other work inflates less.
    """
    import drjit as dr

    from mcrt.tracer import Tracer, lane_layout, pixel_range

    tracer = Tracer(scene, camera, res, res, max_depth, backend=backend)
    k, b = lane_layout(res * res, spp)
    pixels = pixel_range(tracer.m, 0, res * res)
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    times, cpu = [], []
    for seed in range(repeats + 1):
        dr.kernel_history()
        c0 = time.process_time()
        tracer.launch(seed, None, pixels, 0, min(spp, k * b), k, b)
        dr.sync_thread()
        cpu.append(time.process_time() - c0)
        times.append(max(h["execution_time"] for h in dr.kernel_history() if "execution_time" in h) / 1000.0)
    return statistics.median(times[1:]), statistics.median(cpu[1:])


def disassemble(*, camera: str, res: int, spp: int, max_depth: int) -> list[tuple[int, str, str]]:
    """(address, mnemonic, operands) of the largest kernel of one launch, compiled cold in a child process."""
    with tempfile.TemporaryDirectory() as home:
        env = dict(os.environ, HOME=home)  # Dr.Jit's kernel cache lives in $HOME/.drjit: empty, so it compiles
        out = subprocess.run([sys.executable, "-c", _COMPILE_SCRIPT, camera, str(res), str(spp), str(max_depth)],
                             env=env, capture_output=True, text=True, check=True)
    kernels: list[list[tuple[int, str, str]]] = []
    for line in (out.stdout + "\n" + out.stderr).splitlines():
        if "jit_llvm_disasm(): ==========" in line:
            kernels.append([])
            continue
        hit = _DISASM.search(line)
        if hit and kernels:
            kernels[-1].append((int(hit.group(1), 16), hit.group(2), hit.group(3).strip()))
    if not kernels:
        raise RuntimeError("Dr.Jit printed no disassembly (its trace log level did not reach the compiler)")
    return max(kernels, key=len)


def loop_body(code: list[tuple[int, str, str]]) -> list[tuple[int, str, str]]:
    """The path loop: the instructions spanned by the widest backward branch inside the packet loop (the widest)."""
    spans = []
    for i, (addr, op, args) in enumerate(code):
        if op.startswith("j") and re.fullmatch(r"-\d+", args):
            nxt = code[i + 1][0] if i + 1 < len(code) else addr
            spans.append((nxt + int(args), addr))
    spans.sort(key=lambda s: s[1] - s[0], reverse=True)
    if len(spans) < 2:
        raise RuntimeError("no loop inside the packet loop in the disassembly")
    lo, hi = spans[1]
    return [c for c in code if lo <= c[0] <= hi]


def instruction_mix(code) -> dict:
    """Counts of all, vector (any xmm/ymm/zmm operand), 512-bit (zmm) and stack (rsp-relative) instructions."""
    return {"instructions": len(code),
            "vector": sum(bool(re.search(r"\b[xyz]mm\d", a)) for _, _, a in code),
            "zmm": sum("zmm" in a for _, _, a in code),
            "stack": sum("[rsp" in a for _, _, a in code),
            "branches": sum(op.startswith("j") for _, op, _ in code)}


def clock_mhz() -> float | None:
    """The clock /proc/cpuinfo reports (on a virtual machine: the host's nominal clock)."""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("cpu MHz"):
                return float(line.split(":", 1)[1])
    except OSError:
        pass
    return None


def copy_bandwidth(mib: int = 256, repeats: int = 5) -> float:
    """Bytes per second a NumPy copy moves (read plus write), best of ``repeats``: the machine's memory bandwidth."""
    src = np.ones(mib << 18, np.float32)
    dst = np.empty_like(src)
    best = float("inf")
    for _ in range(repeats):
        t0 = time.perf_counter()
        np.copyto(dst, src)
        best = min(best, time.perf_counter() - t0)
    return 2 * src.nbytes / best


def kernel_limits(scene, *, camera: str = "near", res: int = 256, spp: int = 16, max_depth: int = 8,
                  backend: str = "llvm") -> dict:
    """Every measurement of the module docstring for one launch of res x res x spp paths, as a dictionary."""
    from mcrt.tracer import lane_layout

    counts = ray_counts(scene, camera=camera, res=res, spp=spp, max_depth=max_depth, backend=backend)
    seconds, cpu_seconds = kernel_seconds(scene, camera=camera, res=res, spp=spp, max_depth=max_depth, backend=backend)
    code = disassemble(camera=camera, res=res, spp=spp, max_depth=max_depth) if backend == "llvm" else []
    k, _ = lane_layout(res * res, spp)
    # The launch's arrays in memory: the pixel indices (4 B) and the running sums read and written (2 x 6 x 8 B) per
    # pixel, and with k > 1 lanes per pixel the lanes' float64 sums written and read again (2 x 6 x 8 B per lane).
    traffic = res * res * (4 + 96) + (res * res * k * 96 if k > 1 else 0)
    return {"camera": camera, "width": res, "height": res, "spp": spp, "max_depth": max_depth, **counts,
            "kernel_seconds": seconds, "kernel_cpu_seconds": cpu_seconds, "kernel_bytes": traffic,
            "kernel_instructions": instruction_mix(code) if code else None,
            "loop_instructions": instruction_mix(loop_body(code)) if code else None,
            "cores": os.cpu_count(), "clock_mhz": clock_mhz(), "copy_bandwidth": copy_bandwidth(),
            "perf": _perf_note()}


def _perf_note() -> str:
    """What ``perf stat`` says of the hardware counters here, in a few words."""
    try:
        out = subprocess.run(["perf", "stat", "-x,", "-e", "cycles,instructions", "true"], capture_output=True, text=True,
                             timeout=30)
    except (OSError, subprocess.TimeoutExpired):
        return "perf is not installed"
    text = out.stderr
    if "not supported" in text or "<not" in text:
        return "perf stat reports cycles and instructions as not supported (no hardware counters in this virtual machine)"
    return "perf stat counts cycles and instructions here: " + " ".join(text.split())[:120]


if __name__ == "__main__":  # pragma: no cover - a manual check: python -m mcrt.bench_limits
    from mcrt.scene import load_scene

    print(json.dumps(kernel_limits(load_scene()), indent=2))
