"""The ladder: render every (renderer, spp, seed), time it, and measure its error.

Order of work: rung by rung (all seeds and renderers at one spp before the
next), so the progress bar's time left, which extrapolates from the spp done
so far, stays honest while costs grow with spp.

Timing: each renderer first renders once at 1 spp (seed
:data:`~mcrt.convergence.config.WARMUP_SEED`) so that its kernels are compiled
before any timed render; every render's JIT compile time (Dr.Jit's kernel
history) is recorded and subtracted, so ``time = wall_time - compile_time``
is the render time. Renders synchronise before their clock stops.
"""

from __future__ import annotations

import contextlib
import hashlib
import shlex
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

import mcrt  # sets DRJIT_LIBLLVM_PATH before drjit loads
from mcrt import metrics as M
from mcrt.film import Progress, RenderResult
from mcrt.convergence.config import WARMUP_SEED, RendererSpec, ReportConfig, default_cache_dir, render_seed
from mcrt.scene import CANONICAL, Scene, load_scene

#: The metrics stored for every render, with their plot labels.
METRICS = {"rmse": "RMSE", "relmse": "relMSE", "dssim": "1 - SSIM", "flip": "FLIP"}


@dataclass
class Measurement:
    """One render of the ladder and its errors against the reference."""

    renderer: str  # label, e.g. 'mcrt' or 'mcrt K=30'
    spec: str  # 'mcrt', 'mcrt:k30', ...
    rung: int  # index into the ladder
    spp: int
    seed: int  # the report's seed (1, 2, 3, ...)
    render_seed: int  # the seed the renderer got (hash of renderer, seed, spp)
    wall_time: float
    compile_time: float
    time: float  # wall_time - compile_time
    mse: float
    rmse: float
    relmse: float
    ssim: float
    dssim: float
    flip: float
    mse_excess: float  # mse minus the reference's noise floor
    mse_predicted: float  # the render's own estimate of its expected MSE: mean(variance) / spp


@dataclass
class StripImage:
    """What the image strip shows of one (renderer, rung) at the first seed."""

    mean: np.ndarray
    flip_map: np.ndarray  # (H, W) FLIP error in [0, 1]
    rel_error: np.ndarray  # (H, W) per-pixel relative squared error, mean over channels
    flip: float  # mean FLIP error


@dataclass
class ReportData:
    config: ReportConfig
    scene: Scene
    specs: list[RendererSpec]
    ladders: dict[str, list[int]]  # label -> spp per rung
    reference: RenderResult
    reference_info: dict[str, Any]
    flip_params: dict[str, Any]
    floor: dict[str, float]
    warmup: dict[str, dict[str, float]]
    calibration: dict[str, dict[str, float]]
    measurements: list[Measurement]
    strip: dict[tuple[str, int], StripImage]
    provenance: dict[str, Any]
    runtime: float = 0.0


# --------------------------------------------------------------------------
# Renderers
# --------------------------------------------------------------------------


def render_with(spec: RendererSpec, scene: Scene, cfg: ReportConfig, spp: int, seed: int, *, progress: bool = False) -> RenderResult:
    """One render by ``spec`` at the report's camera, size, depth and backend."""
    from mcrt.render import render

    s = scene.settings(camera=cfg.camera, width=cfg.width, height=cfg.height, spp=spp, max_depth=cfg.max_depth,
                       light_samples=spec.shadow_rays(cfg.light_samples))
    return render(scene, s, renderer=spec.kind, seed=seed, backend=cfg.backend, progress=progress)


def _render_time(r: RenderResult) -> tuple[float, float]:
    compile_s = float(r.compile_time or 0.0)
    return float(r.wall_time), compile_s


# --------------------------------------------------------------------------
# Reference
# --------------------------------------------------------------------------


def _versions_key() -> str:
    import drjit as dr
    import mitsuba as mi

    from mcrt.provenance import source_hash

    key = f"{mcrt.__version__}/{source_hash()}/{dr.__version__}/{mi.__version__}"
    return hashlib.blake2b(key.encode(), digest_size=4).hexdigest()


def obtain_reference(cfg: ReportConfig, scene: Scene, *, progress: bool = True, log=print) -> tuple[RenderResult, dict[str, Any]]:
    """The reference image and a description of where it came from.

    With ``cfg.reference`` 'auto' or 'committed', the committed Mitsuba ground
    truth (:func:`mcrt.groundtruth.load_reference`) for this scene, camera,
    size and depth. Otherwise (or when there is none and the mode is 'auto')
    a render by ``cfg.reference_renderer`` at ``cfg.ref_spp()`` spp, cached as
    an EXR in ``cfg.cache_dir`` (default :func:`default_cache_dir`) under a
    name that holds every setting, the scene hash and the versions.
    """
    size = (cfg.width, cfg.height)
    note = ""
    if cfg.reference in ("auto", "committed"):
        from mcrt.groundtruth import ReferenceUnavailable, load_reference, read_manifest, reference_key

        try:
            ref = load_reference(scene, cfg.camera, size, cfg.max_depth)
        except ReferenceUnavailable as e:
            if cfg.reference == "committed":
                raise RuntimeError(str(e)) from None
            note = f"no committed reference: {e}"
        else:
            key = reference_key(scene.name, cfg.camera, size, cfg.max_depth)
            entry = read_manifest()["references"].get(key, {})
            info = {
                "source": "committed",
                "description": f"committed Mitsuba 3 reference {key} ({ref.spp} spp, path integrator), reference/{entry.get('file', key + '.exr')}",
                "key": key, "file": f"reference/{entry.get('file', key + '.exr')}", "sha256": entry.get("sha256"),
                "renderer": ref.renderer, "spp": ref.spp, "seed": ref.seed,
                "mitsuba_version": ref.extra.get("mitsuba_version"), "variant": ref.extra.get("variant"),
            }
            return ref, info
    spec = RendererSpec.parse(cfg.reference_renderer)
    spp = cfg.ref_spp()
    seed = render_seed(spec, cfg.reference_seed, spp) ^ 0x5EED
    cache = Path(cfg.cache_dir) if cfg.cache_dir else default_cache_dir()
    k = spec.shadow_rays(cfg.light_samples)
    key = (f"{scene.name}_{cfg.camera}_{cfg.width}x{cfg.height}_d{cfg.max_depth}_{spec.kind}{'' if k is None else f'_k{k}'}"
           f"_{spp}spp_s{seed}_{scene.content_hash()[:12]}_{cfg.backend}_{_versions_key()}")
    path = cache / f"{key}.exr"
    from mcrt.image_files import ImageError, read_exr, write_exr

    ref = None
    if path.exists():
        try:
            ref = read_exr(path)
            if ref.spp != spp or ref.seed != seed or ref.scene_hash != scene.content_hash() or ref.shape != (cfg.height, cfg.width):
                ref = None
        except ImageError:
            ref = None
    source = "cached render"
    if ref is None:
        log(f"report: rendering the reference: {spec.label}, {cfg.width}x{cfg.height}, {spp} spp (cached in {path})")
        ref = render_with(spec, scene, cfg, spp, seed, progress=progress)
        with contextlib.suppress(OSError):
            cache.mkdir(parents=True, exist_ok=True)
            write_exr(path, ref)
        source = "rendered"
    what = "Mitsuba 3 (path integrator)" if spec.kind == "mitsuba" else spec.label
    info = {
        "source": source,
        "description": (f"a {spp}-spp render by {what} (seed {seed}), {'read from' if source == 'cached render' else 'rendered now and cached in'} "
                        f"{path} (not committed: the same command renders it again, bit for bit, from its seed)"
                        + (f"; {note}" if note else "")),
        "key": key, "file": str(path), "sha256": None, "renderer": ref.renderer, "spec": spec.text,
        "spp": ref.spp, "seed": seed, "render_wall_time": ref.wall_time,
    }
    return ref, info


def reference_floor(ref: RenderResult) -> dict[str, float]:
    """The expected squared error that the reference's noise adds: mean(var_ref / spp_ref), and its relMSE analogue."""
    if ref.variance is None or ref.spp < 2:
        return {"mse": 0.0, "relmse": 0.0, "known": False}
    v = np.maximum(ref.variance.astype(np.float64), 0.0) / ref.spp
    m = ref.mean.astype(np.float64)
    return {"mse": float(v.mean()), "relmse": float((v / (m * m + M.RELMSE_EPS)).mean()), "known": True}


# --------------------------------------------------------------------------
# The ladder
# --------------------------------------------------------------------------


def _strip_rungs(cfg: ReportConfig) -> list[int]:
    ladder = list(cfg.spp_ladder)
    if cfg.strip_spp:
        return [ladder.index(s) for s in cfg.strip_spp]
    n = len(ladder)
    return sorted({0, n // 2, n - 1})


class CostModel:
    """Seconds per job (render + metrics) of each renderer as a + b spp, fitted to the jobs done so far."""

    def __init__(self):
        self.points: dict[str, list[tuple[int, float]]] = {}

    def add(self, label: str, spp: int, seconds: float) -> None:
        self.points.setdefault(label, []).append((int(spp), float(seconds)))

    def predict(self, label: str, spp: int) -> float:
        pts = self.points.get(label) or [p for v in self.points.values() for p in v]
        if not pts:
            return 1.0
        x = np.array([p[0] for p in pts], dtype=np.float64)
        y = np.array([p[1] for p in pts])
        if np.ptp(x) == 0:
            a, b = 0.0, float(y.mean() / x[0])  # one sample count seen: assume cost grows with spp
        else:
            b, a = np.polyfit(x, y, 1)
            b = max(float(b), 0.0)
            a = max(float(a), 0.0) if b > 0 else float(y.mean())
        return a + b * spp


def run_ladder(cfg: ReportConfig, *, progress: bool = True, command: str | None = None, log=None) -> ReportData:
    """Render the whole ladder of ``cfg`` and measure every render; writes nothing."""
    cfg.check()
    quiet = not progress
    log = log or (lambda msg: None if quiet else print(msg, file=sys.stderr, flush=True))
    t_start = time.perf_counter()
    scene = load_scene(cfg.scene or CANONICAL)
    scene.camera(cfg.camera)  # fail early on a bad camera name
    specs = cfg.specs()
    from mcrt.provenance import provenance

    prov = provenance(packages=("scikit-image", "flip-evaluator", "matplotlib", "scipy"),
                      command=command or " ".join(shlex.quote(a) for a in sys.argv), backend=cfg.backend)

    ref, ref_info = obtain_reference(cfg, scene, progress=progress, log=log)
    if ref.shape != (cfg.height, cfg.width):
        raise RuntimeError(f"reference is {ref.shape[1]}x{ref.shape[0]}, the report renders {cfg.width}x{cfg.height}")
    log(f"report: reference: {ref_info['description']}")
    flip_params = M.flip_parameters(ref.mean)
    floor = reference_floor(ref)

    def job(spec: RendererSpec, spp: int, seed: int) -> tuple[RenderResult, float, float, np.ndarray, float]:
        """Render and measure; returns the render, MSE, SSIM, FLIP map and mean FLIP."""
        r = render_with(spec, scene, cfg, spp, seed)
        fmap, fmean = M.flip_map(ref.mean, r.mean, flip_params)
        return r, M.mse(ref.mean, r.mean), M.ssim(ref.mean, r.mean), fmap, fmean

    # Warm-up (compiles the kernels), then two untimed probes (1 and n spp) that
    # start the cost model of the progress bar and calibrate equal-time mode.
    cost = CostModel()
    warmup: dict[str, dict[str, float]] = {}
    calibration: dict[str, dict[str, float]] = {}
    n = cfg.probe_spp()
    for spec in specs:
        r = render_with(spec, scene, cfg, 1, WARMUP_SEED)
        warmup[spec.label] = {"spp": 1, "wall_time": r.wall_time, "compile_time": float(r.compile_time or 0.0)}
        log(f"report: warm-up {spec.label}: {r.wall_time:.2f} s (JIT compile {float(r.compile_time or 0):.2f} s)")
        for k, spp in enumerate(sorted({1, n})):
            t0 = time.perf_counter()
            r = job(spec, spp, WARMUP_SEED + 1 + k)[0]
            cost.add(spec.label, spp, time.perf_counter() - t0)
        wall, comp = _render_time(r)
        calibration[spec.label] = {"spp": n, "time": wall - comp, "time_per_spp": (wall - comp) / n}

    ladders = {s.label: list(cfg.spp_ladder) for s in specs}
    if cfg.equal_time:
        lead = specs[0].label
        for spec in specs[1:]:
            factor = calibration[lead]["time_per_spp"] / calibration[spec.label]["time_per_spp"]
            calibration[spec.label]["spp_factor"] = factor
            ladders[spec.label] = [max(1, int(round(s * factor))) for s in cfg.spp_ladder]
        log("report: equal time: " + "; ".join(f"{k}: {v['time_per_spp'] * 1000:.0f} ms/spp" for k, v in calibration.items())
            + f"; ladders {ladders}")

    strip_rungs = _strip_rungs(cfg)
    jobs = [(rung, seed, spec) for rung in range(len(cfg.spp_ladder)) for seed in cfg.seeds for spec in specs]
    bar = Progress(len(jobs), label="report", unit="renders", enabled=progress)
    measurements: list[Measurement] = []
    strip: dict[tuple[str, int], StripImage] = {}
    for i, (rung, seed, spec) in enumerate(jobs):
        spp = ladders[spec.label][rung]
        rs = render_seed(spec, seed, spp)
        t0 = time.perf_counter()
        r, mse, s, fmap, fmean = job(spec, spp, rs)
        cost.add(spec.label, spp, time.perf_counter() - t0)
        wall, comp = _render_time(r)
        measurements.append(Measurement(
            renderer=spec.label, spec=spec.text, rung=rung, spp=spp, seed=seed, render_seed=rs,
            wall_time=wall, compile_time=comp, time=max(wall - comp, 1e-9),
            mse=mse, rmse=float(np.sqrt(mse)), relmse=M.relmse(ref.mean, r.mean), ssim=s, dssim=1.0 - s, flip=fmean,
            mse_excess=mse - floor["mse"],
            mse_predicted=float(np.mean(r.variance, dtype=np.float64) / spp) if r.variance is not None and spp > 1 else float("nan"),
        ))
        if rung in strip_rungs and seed == cfg.seeds[0]:
            strip[(spec.label, rung)] = StripImage(mean=r.mean.copy(), flip_map=fmap, rel_error=M.relmse_map(ref.mean, r.mean),
                                                   flip=fmean)
        left = sum(cost.predict(sp.label, ladders[sp.label][rg]) for rg, _, sp in jobs[i + 1:])
        bar.label = f"report (last: {spec.label}, {spp} spp, seed {seed})"
        bar.update(i + 1, left)

    return ReportData(
        config=cfg, scene=scene, specs=specs, ladders=ladders, reference=ref, reference_info=ref_info,
        flip_params=flip_params, floor=floor, warmup=warmup, calibration=calibration, measurements=measurements,
        strip=strip, provenance=prov, runtime=time.perf_counter() - t_start,
    )
