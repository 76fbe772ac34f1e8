"""The tricks study: every variant rendered at a ladder of spp and several seeds, measured against the reference.

For each (variant, spp, seed) the render is timed (wall time less JIT
compilation; a warm-up render per variant compiles its kernels first) and
measured against the committed Mitsuba reference with the project's
metrics (:mod:`mcrt.metrics`: RMSE, relMSE) and the project's comparison
(:func:`mcrt.stats.policy.compare`, policy ``'reference-floor'``; an
adaptive render's floor at each pixel's own count,
:func:`mcrt.tricks.adaptive.floor_at_counts`) at two tile sizes, the
suite's 8 x 8 and 32 x 32, which sees a bias spread thinly over large
regions; each at alpha / 2, so that a correct render is flagged with
probability at most alpha. Over the seeds of one (variant, spp):

    MSE = bias^2 + variance + floor,

with ``variance`` the mean over pixels and channels of the variance of
the image across seeds and ``floor`` the reference's own noise
(:func:`mcrt.convergence.run.reference_floor`), so bias^2 = MSE - variance -
floor (it can come out negative by chance: then no bias is measurable).
"""

from __future__ import annotations

import hashlib
import time
from dataclasses import asdict, dataclass, field

import numpy as np

from mcrt import metrics as M
from mcrt.film import Progress, RenderResult
from mcrt.scene import Scene
from mcrt.tricks.variants import Variant

#: Seed of the warm-up renders (they only compile kernels).
WARMUP_SEED = 424_242


@dataclass(frozen=True)
class StudyConfig:
    """What the study renders and how it compares."""

    camera: str = "near"
    res: int = 64
    max_depth: int = 8
    ladder: tuple[int, ...] = (16, 64, 256, 1024, 4096)
    seeds: int = 4
    alpha: float = 0.01
    tiles: tuple[int, ...] = (8, 32)
    aov_spp: int = 16
    backend: str = "llvm"


@dataclass
class Measurement:
    """One render of one variant, measured against the reference."""

    label: str
    trick: str
    spp: int  # the rung: samples per pixel of the budget
    seed: int  # the study's seed (0, 1, ...)
    render_seed: int
    time: float  # wall time - JIT compile time [s]
    samples: float  # samples traced per pixel, on average (adaptive: the budget, pilot included)
    mse: float
    mse_excess: float  # mse - the reference's noise floor
    rmse: float
    relmse: float
    passed: bool  # the comparisons with the reference found no difference
    rejected: tuple  # tiles each comparison rejected (one per tile size)
    rejected_darker: int  # of those, the tiles darker than the reference (t < 0)
    whole_image: float  # the whole image's (A - B) / mean(|A|, |B|), mean over channels


@dataclass
class Rung:
    """One (variant, spp) over its seeds."""

    label: str
    trick: str
    spp: int
    time: float  # median over seeds
    time_plain: float  # median of plain mcrt's renders at this spp timed between this variant's (the paired time)
    mse: float
    relmse: float
    rmse: float
    variance: float  # mean over pixels and channels of the image's variance across seeds
    bias2: float  # mse - variance - floor
    flagged: int  # seeds whose comparison with the reference failed
    seeds: int
    efficiency: float  # 1 / (mse_excess x time)


@dataclass
class StudyData:
    config: StudyConfig
    scene: Scene
    variants: list[Variant]
    reference_key: str
    reference_spp: int
    floor: dict
    measurements: list[Measurement] = field(default_factory=list)
    rungs: list[Rung] = field(default_factory=list)
    images: dict = field(default_factory=dict)  # label -> mean image at the top rung, seed 0
    spp_maps: dict = field(default_factory=dict)  # label -> (H, W) samples traced per pixel there (adaptive)
    variance_maps: dict = field(default_factory=dict)  # label -> (H, W) per-sample variance there (luminance-free mean)
    extra: dict = field(default_factory=dict)  # what other parts of the study add (spp maps, light receivers)
    runtime: float = 0.0


def render_seed(label: str, seed: int, spp: int) -> int:
    """A 31-bit hash of (variant, seed, spp): every render of the study draws its own streams."""
    key = f"mcrt.tricks/{label}/{int(seed)}/{int(spp)}".encode()
    return int.from_bytes(hashlib.blake2b(key, digest_size=4).digest(), "little") & 0x7FFFFFFF


def compare_with_reference(r: RenderResult, ref: RenderResult, adaptive, *, alpha: float, tiles) -> list:
    """The comparisons of the study: one per tile size at alpha / len(tiles), the variance floored at the reference's."""
    from mcrt.stats.policy import compare
    from mcrt.tricks.adaptive import floor_at_counts

    a = alpha / len(tiles)
    if adaptive is not None:
        floored = floor_at_counts(adaptive, ref)
        return [compare(floored, ref, policy="independent", alpha=a, tile=t) for t in tiles]
    return [compare(r, ref, policy="reference-floor", alpha=a, tile=t) for t in tiles]


def _measure(v: Variant, r: RenderResult, adaptive, ref: RenderResult, floor: dict, cfg: StudyConfig, spp: int,
             seed: int, rseed: int, extra_time: float) -> Measurement:
    mse = M.mse(ref.mean, r.mean)
    cs = compare_with_reference(r, ref, adaptive, alpha=cfg.alpha, tiles=cfg.tiles)
    return Measurement(
        label=v.label, trick=v.trick, spp=spp, seed=seed, render_seed=rseed,
        time=float(r.wall_time) - float(r.compile_time or 0.0) + extra_time,
        samples=float(r.extra.get("samples_per_pixel", r.spp)), mse=mse, mse_excess=mse - floor["mse"],
        rmse=float(np.sqrt(mse)), relmse=M.relmse(ref.mean, r.mean), passed=all(c.passed for c in cs),
        rejected=tuple(int(c.n_rejected) for c in cs), rejected_darker=sum(int(((c.t < 0) & c.rejected).sum()) for c in cs),
        whole_image=float(np.mean(cs[0].global_rel_diff)),
    )


def _rung(v: Variant, spp: int, ms: list[Measurement], images: list[np.ndarray], floor: dict, plain_times) -> Rung:
    stack = np.stack([im.astype(np.float64) for im in images])
    variance = float(stack.var(axis=0, ddof=1).mean()) if len(images) > 1 else float("nan")
    mse = float(np.mean([m.mse for m in ms]))
    t = float(np.median([m.time for m in ms]))  # the median: a rung's first render also records its kernels
    excess = mse - floor["mse"]
    return Rung(
        label=v.label, trick=v.trick, spp=spp, time=t, time_plain=float(np.median(plain_times)) if plain_times else t,
        mse=mse, relmse=float(np.mean([m.relmse for m in ms])),
        rmse=float(np.mean([m.rmse for m in ms])), variance=variance, bias2=mse - variance - floor["mse"],
        flagged=sum(not m.passed for m in ms), seeds=len(ms),
        efficiency=1.0 / (excess * t) if excess > 0 and t > 0 else float("nan"),
    )


def run_study(scene: Scene, variants: list[Variant], cfg: StudyConfig, *, progress: bool = True, log=print) -> StudyData:
    """Render every variant at every rung and seed; measure and aggregate (writes nothing)."""
    from mcrt.groundtruth import load_reference
    from mcrt.convergence.run import reference_floor
    from mcrt.tricks.aov import first_hit_buffers

    t_start = time.perf_counter()
    ref = load_reference(scene, cfg.camera, (cfg.res, cfg.res), cfg.max_depth)
    floor = reference_floor(ref)
    data = StudyData(cfg, scene, variants, f"{scene.name}_{cfg.camera}_{cfg.res}x{cfg.res}_d{cfg.max_depth}", ref.spp, floor)
    settings = scene.settings(camera=cfg.camera, width=cfg.res, height=cfg.res, spp=1, max_depth=cfg.max_depth)
    buffers, aov_time = _buffers(scene, cfg, first_hit_buffers)
    data.extra["aov_time"] = aov_time
    total = len(variants) * cfg.seeds * sum(cfg.ladder)
    bar = Progress(total, label="mcrt tricks", enabled=progress)
    done = 0
    # Variant by variant, so that each variant's tracer stays compiled and cached while it renders; plain
    # mcrt is timed between a variant's renders, so that the time ratio sees the same load of the machine.
    plain = variants[0]
    plain.render(scene, _at(settings, 2), WARMUP_SEED, backend=cfg.backend)
    for v in variants:
        v.render(scene, _at(settings, 2), WARMUP_SEED, buffers=buffers, backend=cfg.backend)  # compile first
        for spp in cfg.ladder:
            ms, images, plain_times = [], [], []
            for seed in range(cfg.seeds):
                if v is not plain and seed % 2 == 1:
                    pr, _ = plain.render(scene, _at(settings, spp), render_seed("timing", seed, spp), backend=cfg.backend)
                    plain_times.append(float(pr.wall_time) - float(pr.compile_time or 0.0))
                rseed = render_seed(v.label, seed, spp)
                r, adaptive = v.render(scene, _at(settings, spp), rseed, buffers=buffers, backend=cfg.backend)
                ms.append(_measure(v, r, adaptive, ref, floor, cfg, spp, seed, rseed,
                                   aov_time if v.denoise == "albedo+normal" else 0.0))
                images.append(r.mean)
                if spp == cfg.ladder[-1] and seed == 0:
                    data.images[v.label] = r.mean
                    if adaptive is not None:
                        data.spp_maps[v.label] = adaptive.traced
                    elif v.denoise is None and r.variance is not None:
                        data.variance_maps[v.label] = r.variance.mean(axis=2)
                done += spp
                bar.update(done)
            data.measurements += ms
            data.rungs.append(_rung(v, spp, ms, images, floor, plain_times))
    data.images["reference"] = ref.mean
    data.runtime = time.perf_counter() - t_start
    return data


def confirm_unbiased(data: StudyData, labels: list[str], spp: int, *, backend: str = "llvm", log=print) -> dict:
    """One render of each of ``labels`` at ``spp``, compared as in the study: does a flag at the top rung persist?

    An unbiased estimator with heavy tails (a fixed small survival
    probability multiplies rare paths' weights by 1/q per vertex) has a
    skewed mean: at moderate spp it is more often low, with a low variance
    estimate, and the comparison rejects it on the dark side; the flag goes
    away with more samples, a bias's does not.
    """
    from mcrt.groundtruth import load_reference

    cfg = data.config
    ref = load_reference(data.scene, cfg.camera, (cfg.res, cfg.res), cfg.max_depth)
    settings = data.scene.settings(camera=cfg.camera, width=cfg.res, height=cfg.res, spp=spp, max_depth=cfg.max_depth)
    out = {}
    for label in labels:
        v = next(x for x in data.variants if x.label == label)
        log(f"mcrt tricks: {label}: flagged although unbiased in theory; one render at {spp} spp")
        r, adaptive = v.render(data.scene, settings, render_seed(label, -1, spp), backend=backend)
        m = _measure(v, r, adaptive, ref, data.floor, cfg, spp, -1, render_seed(label, -1, spp), 0.0)
        out[label] = {"spp": spp, "passed": m.passed, "rejected": list(m.rejected), "rejected_darker": m.rejected_darker,
                      "whole_image": m.whole_image}
    return out


def _at(settings, spp: int):
    from dataclasses import replace

    return replace(settings, spp=int(spp))


def _buffers(scene: Scene, cfg: StudyConfig, first_hit_buffers):
    """The denoiser's guides, and the time tracing them takes once compiled (added to each denoised render)."""
    first_hit_buffers(scene, cfg.camera, cfg.res, cfg.res, spp=cfg.aov_spp, backend=cfg.backend)
    t0 = time.perf_counter()
    b = first_hit_buffers(scene, cfg.camera, cfg.res, cfg.res, spp=cfg.aov_spp, backend=cfg.backend)
    return b, time.perf_counter() - t0


def measurement_dicts(data: StudyData) -> list[dict]:
    return [asdict(m) for m in data.measurements]


def rung_dicts(data: StudyData) -> list[dict]:
    return [asdict(r) for r in data.rungs]
