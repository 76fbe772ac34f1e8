"""What a submission is compared with: references, the noise model, the mutants' expected images.

:func:`prepare_context` builds a :class:`Context` once per grading run, in
the grading process, before any student is graded; workers receive it
ready-made (the one render a worker may make is the small correct render
that tells too few samples from a noisy bug, in
:mod:`mcrt.grade.grader`).

* References, one per camera of the scene, at the grade resolution: the
  committed Mitsuba reference (:func:`mcrt.groundtruth.load_reference`) when
  one exists at that resolution or at an integer multiple of it (box-filtered
  down: with a box reconstruction filter the expected image of a coarser
  render is the block mean of a finer one), otherwise a high-spp mcrt render.
* The noise model: mcrt's per-sample variance at the grade resolution, from
  the diagnosis baseline render (``diagnosis_spp`` samples per pixel).
* The catalogue's expected images: every mutant of :data:`mcrt.mutants.MUTANTS`
  rendered by mcrt at the grade resolution with the same seed as the
  baseline (common random numbers: ``mutant - baseline`` is much less noisy
  than either image).
* The scene's variations (each surface's albedo, the light, the objects,
  the eye, the path depth, a finer image for camera warps) that
  :mod:`mcrt.grade.explain` fits to a failing image.
* Per camera, the surface each pixel sees (:func:`surface_labels`) and the
  share of direct light (a max-depth-2 image over the full image), for
  describing *where* an image is wrong.

Renders are cached as OpenEXR files (mean and per-sample variance) under the
cache folder, keyed by the scene's content hash and every setting that
changes the image (the render settings with the seed, the mutant, mcrt's
version and source hash), so each is rendered once per machine.
"""

from __future__ import annotations

import hashlib
import json
import os
import time
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path

import numpy as np

from mcrt.film import RenderResult
from mcrt.grade.assignment import Assignment
from mcrt.scene import Lambertian, Mirror, RenderSettings, Scene
from mcrt.stats import LUMINANCE_WEIGHTS
from mcrt.stats.tiles import block_means

CACHE_ENV = "MCRT_CACHE"
DIRECT_SPP = 256  # spp of the max-depth-2 images used to describe regions (mcrt fallback)


def default_cache_dir() -> Path:
    env = os.environ.get(CACHE_ENV)
    if env:
        return Path(env) / "grade"
    return Path(os.environ.get("XDG_CACHE_HOME", Path.home() / ".cache")) / "mcrt" / "grade"


@dataclass
class Expected:
    """An expected image at the grade resolution: mean, per-sample variance, sample count."""

    mean: np.ndarray
    var: np.ndarray
    spp: int
    source: str


@dataclass
class Context:
    """Everything a worker needs to grade a student, picklable."""

    assignment: Assignment
    scene_hash: str
    cameras: tuple[str, ...]
    references: dict[str, Expected]  # camera -> reference at grade resolution
    model_var: dict[str, np.ndarray]  # camera -> mcrt per-sample variance (noise model)
    baseline: Expected  # mcrt, assigned camera, diagnosis seed
    mutants: dict[str, Expected]  # mutant -> mcrt expected image, assigned camera, same seed as baseline
    mutant_texts: dict[str, str]
    direct_fraction: dict[str, np.ndarray]  # camera -> (H, W) share of direct light (luminance)
    labels: dict[str, np.ndarray]  # camera -> (H, W) surface index
    label_names: tuple[str, ...]
    prepare_time: float = 0.0
    notes: list[str] = field(default_factory=list)
    explain: object = None  # mcrt.grade.explain.Basis: the scene's variations, for explaining a failing image
    # mcrt without light sampling (the light found by bounces alone), assigned camera, diagnosis spp and seed, and its
    # per-sample variance by camera: a correct tracer without next-event estimation, whose noise the noise criterion
    # tells from fewer samples by its shape (mcrt.grade.stages.noise.unsampled_shape)
    unsampled: Expected | None = None
    model_var_unsampled: dict[str, np.ndarray] = field(default_factory=dict)


# --------------------------------------------------------------------------
# Box filtering between resolutions
# --------------------------------------------------------------------------


def downsample_result(r: RenderResult, k: int) -> RenderResult:
    """A render box-filtered by k: the block means, with the stratified per-sample variance.

    Each coarse pixel's mean averages k^2 fine pixels of ``spp`` samples, so it
    is a stratified estimate of ``k^2 spp`` samples whose variance is
    ``mean_j(var_j) / (k^2 spp)``: the coarse per-sample variance is the mean
    of the fine ones and the sample count is ``k^2 spp``.
    """
    if k == 1:
        return r
    var = None if r.variance is None else block_means(r.variance.astype(np.float64), k).astype(np.float32)
    return RenderResult(mean=block_means(r.mean.astype(np.float64), k).astype(np.float32), variance=var,
                        spp=r.spp * k * k, seed=r.seed, max_depth=r.max_depth, renderer=r.renderer,
                        scene_hash=r.scene_hash, camera=r.camera, extra=dict(r.extra))


# --------------------------------------------------------------------------
# Cached mcrt renders
# --------------------------------------------------------------------------


def grading_settings(scene: Scene, camera: str, w: int, h: int, max_depth: int, spp: int, seed: int) -> RenderSettings:
    """The settings of every mcrt render grading makes: one shadow ray per diffuse vertex, the scene's Russian roulette."""
    return scene.settings(camera=camera, width=w, height=h, spp=spp, max_depth=max_depth, light_samples=1, seed=seed)


def _cache_key(scene: Scene, s: RenderSettings, mutant: str, tricks: dict | None = None) -> str:
    import mcrt
    from mcrt.provenance import source_hash

    desc = {"scene": scene.content_hash(), "settings": asdict(s), "mutant": mutant, "mcrt": mcrt.__version__,
            "source": source_hash(), **({"tricks": tricks} if tricks else {})}
    digest = hashlib.sha256(json.dumps(desc, sort_keys=True).encode()).hexdigest()[:12]
    what = mutant + "".join(f"_{k}{v:g}" if isinstance(v, float) else f"_{k}{v}"
                            for k, v in sorted((tricks or {}).items()))
    return f"{scene.name}_{s.camera}_{s.width}x{s.height}_d{s.max_depth}_{what}_{s.spp}spp_s{s.seed}_{digest}"


def cached_render(scene: Scene, camera: str, w: int, h: int, max_depth: int, spp: int, seed: int, mutant: str,
                  cache_dir: Path, log=None, tricks: dict | None = None) -> RenderResult:
    """An mcrt render (:func:`grading_settings`) from the cache, rendered and stored on a miss.

    ``mutant='none'``: no bug; ``tricks``: the renderer's estimator tricks
    (:data:`mcrt.options.TRICK_OPTIONS`), as a mistake rendered for the
    explanation, such as a per-sample clamp.
    """
    from mcrt.image_files import ImageError, read_exr, write_exr
    from mcrt.render import render

    s = grading_settings(scene, camera, w, h, max_depth, spp, seed)
    path = Path(cache_dir) / (_cache_key(scene, s, mutant, tricks) + ".exr")
    if path.exists():
        try:
            r = read_exr(path)
            if r.mean.shape == (h, w, 3) and r.variance is not None and r.spp == spp:
                return r
        except ImageError:
            pass
    t0 = time.perf_counter()
    r = render(scene, s, seed=seed, progress=False, mutants=() if mutant == "none" else (mutant,), **(tricks or {}))
    if log:
        log(f"  rendered {camera} {w}x{h} d{max_depth} {mutant} at {spp} spp in {time.perf_counter() - t0:.1f} s")
    path.parent.mkdir(parents=True, exist_ok=True)
    try:
        write_exr(path, r)
    except ImageError as e:  # a read-only cache still grades
        if log:
            log(f"  warning: cannot cache {path.name}: {e}")
    return r


def _committed(scene: Scene, camera: str, w: int, h: int, max_depth: int) -> RenderResult | None:
    """The committed Mitsuba reference at (w, h) or at an integer multiple, box-filtered down."""
    from mcrt.groundtruth import load_reference

    for k in (1, 2, 3, 4, 5, 6, 8, 10, 12, 16):
        if w * k > 2048:
            break
        try:
            r = load_reference(scene, camera, (w * k, h * k), max_depth)
        except Exception:  # noqa: BLE001, S112 - missing, stale or corrupt: fall back to the next size or mcrt
            continue
        if r.variance is None or r.mean.shape != (h * k, w * k, 3):
            continue
        return downsample_result(r, k)
    return None


def _expected(r: RenderResult, source: str) -> Expected:
    return Expected(r.mean.astype(np.float32), np.maximum(r.variance, 0).astype(np.float32), int(r.spp), source)


def reference_for(a: Assignment, scene: Scene, camera: str, max_depth: int, spp: int, cache_dir: Path, log=None) -> Expected:
    """The reference for one camera at the grade resolution (see the module docstring)."""
    w, h = a.grade_width, a.grade_height
    if a.reference in ("auto", "mitsuba"):
        r = _committed(scene, camera, w, h, max_depth)
        if r is not None:
            return _expected(r, f"Mitsuba 3 committed reference ({r.spp} samples per grade pixel)")
        if a.reference == "mitsuba":
            raise RuntimeError(f"no committed Mitsuba reference for {scene.name} camera {camera} at {w}x{h} "
                               f"(or a multiple) with max depth {max_depth}; build one with `mcrt reference build`, "
                               f"or set grading.reference = \"auto\"")
    r = cached_render(scene, camera, w, h, max_depth, spp, a.seed + 1, "none", cache_dir, log)
    return _expected(r, f"mcrt render ({spp} spp, cached)")


def prepare_context(a: Assignment, cache_dir: str | os.PathLike | None = None, *, mutants=None, log=None,
                    explain: bool = True) -> Context:
    """Render or load everything grading needs (see the module docstring).

    ``mutants`` restricts the catalogue (default: all of it); ``log`` is a
    callable taking one line of progress text; ``explain`` (default true)
    renders the scene's variations that explain a failing image
    (:func:`mcrt.grade.explain.families.prepare`).
    """
    from mcrt.mutants import MUTANTS

    t0 = time.perf_counter()
    cache = Path(cache_dir) if cache_dir is not None else default_cache_dir()
    scene = a.load_scene()
    w, h, d = a.grade_width, a.grade_height, a.max_depth
    cams = tuple(scene.cameras)
    refs, model, direct, labels = {}, {}, {}, {}
    names = mutants if mutants is not None else tuple(MUTANTS)
    baseline = cached_render(scene, a.camera, w, h, d, a.diagnosis_spp, a.seed, "none", cache, log)
    for cam in cams:
        refs[cam] = reference_for(a, scene, cam, d, a.reference_spp, cache, log)
        if cam == a.camera:
            model[cam] = np.maximum(baseline.variance, 0).astype(np.float32)
            unsampled = cached_render(scene, cam, w, h, d, a.diagnosis_spp, a.seed, "none", cache, log,
                                      tricks={"light_sampling": "none"})
            model_unsampled = {cam: np.maximum(unsampled.variance, 0).astype(np.float32)}
        else:  # the reference's own variance is the noise model's best stand-in for another camera
            other = cached_render(scene, cam, w, h, d, a.diagnosis_spp // 4 or 16, a.seed, "none", cache, log) \
                if refs[cam].source.startswith("Mitsuba") else None
            model[cam] = (np.maximum(other.variance, 0) if other is not None else refs[cam].var).astype(np.float32)
        d2 = _committed(scene, cam, w, h, 2) if d != 2 else None
        if d2 is None:
            d2 = cached_render(scene, cam, w, h, 2, DIRECT_SPP, a.seed + 2, "none", cache, log)
        direct[cam] = _direct_fraction(d2.mean, refs[cam].mean, d)
        labels[cam] = surface_labels(scene, cam, w, h)
    muts, notes = {}, []
    for m in names:
        try:
            r = cached_render(scene, a.camera, w, h, d, a.diagnosis_spp, a.seed, m, cache, log)
        except ValueError as e:  # a mutant this scene cannot have (albedo_1pct needs a wall BC)
            notes.append(f"mutant {m} left out of the diagnosis: {e}")
            continue
        muts[m] = _expected(r, f"mcrt with mutant {m} ({a.diagnosis_spp} spp)")
    from mcrt.grade.explain.families import prepare as prepare_basis

    def render_cached(sc, cam, width, height, depth, spp, seed, **tricks):
        return cached_render(sc, cam, width, height, depth, spp, seed, "none", cache, log, tricks=tricks)

    basis = prepare_basis(a, scene, render_cached) if explain else None
    return Context(
        assignment=a, scene_hash=scene.content_hash(), cameras=cams, references=refs, model_var=model,
        baseline=_expected(baseline, f"mcrt ({a.diagnosis_spp} spp)"), mutants=muts,
        mutant_texts={m: MUTANTS[m] for m in names}, direct_fraction=direct, labels=labels,
        label_names=label_names(scene), prepare_time=time.perf_counter() - t0, notes=notes, explain=basis,
        unsampled=_expected(unsampled, f"mcrt without light sampling ({a.diagnosis_spp} spp)"),
        model_var_unsampled=model_unsampled,
    )


def _direct_fraction(direct: np.ndarray, full: np.ndarray, max_depth: int) -> np.ndarray:
    """Share of each pixel's luminance that max depth 2 (emission + direct light) already gives."""
    lum = np.asarray(LUMINANCE_WEIGHTS)
    dl, fl = direct.astype(np.float64) @ lum, full.astype(np.float64) @ lum
    if max_depth in (1, 2):
        return np.ones_like(fl)
    with np.errstate(divide="ignore", invalid="ignore"):
        f = np.where(fl > 0, dl / fl, 1.0)
    return np.clip(f, 0.0, 1.0).astype(np.float32)


# --------------------------------------------------------------------------
# What each pixel sees
# --------------------------------------------------------------------------

_COLOURS = {
    "red": (0.75, 0.15, 0.15), "green": (0.15, 0.70, 0.15), "blue": (0.15, 0.20, 0.75), "yellow": (0.75, 0.70, 0.15),
    "purple": (0.55, 0.15, 0.70), "cyan": (0.15, 0.65, 0.70), "orange": (0.80, 0.45, 0.10), "grey": (0.6, 0.6, 0.6),
    "white": (0.85, 0.85, 0.85), "black": (0.0, 0.0, 0.0),
}


def colour_name(rgb) -> str:
    """The nearest of a few colour names to an albedo (after normalising brightness for greys)."""
    rgb = np.asarray(rgb, float)
    best = min(_COLOURS, key=lambda k: float(np.sum((np.asarray(_COLOURS[k]) - rgb) ** 2)))
    if best in ("grey", "white", "black"):
        m = rgb.mean()
        return "white" if m > 0.75 else "black" if m < 0.05 else "grey"
    return best


def label_names(scene: Scene) -> tuple[str, ...]:
    """Human names of the surfaces of :func:`surface_labels`, by index; the last is 'nothing'."""
    names = []
    for s in scene.surfaces():
        if s.name.startswith("wall_"):
            names.append(f"wall {s.name[5:]} ({colour_name(s.material.albedo)})")
        elif s.material is None:
            names.append("the light")
        elif isinstance(s.material, Lambertian):
            names.append(f"the {s.name}" if s.name in ("floor", "ceiling") else f"the {s.name} ({colour_name(s.material.albedo)})")
        else:
            names.append(f"the {s.name}")
    for sp in scene.spheres():
        names.append(f"the mirror {sp.name}" if isinstance(sp.material, Mirror) else f"the {sp.name}")
    names.append("nothing")
    return tuple(names)


def surface_labels(scene: Scene, camera: str, width: int, height: int, sub: int = 4) -> np.ndarray:
    """(H, W) index into :func:`label_names` of the surface most of each pixel sees (sub x sub rays)."""
    from mcrt.grade.hits import first_hits

    return np.argmax(first_hits(scene, camera, width, height, sub).counts, axis=2).astype(np.int16)




# --------------------------------------------------------------------------
# A coarser view of a context (hand-ins smaller than the grade resolution)
# --------------------------------------------------------------------------


def _coarse_expected(e: Expected, k: int) -> Expected:
    return Expected(block_means(e.mean.astype(np.float64), k).astype(np.float32),
                    block_means(e.var.astype(np.float64), k).astype(np.float32), e.spp * k * k, e.source + f", box-filtered by {k}")


def _mode_blocks(lab: np.ndarray, k: int, n: int) -> np.ndarray:
    h, w = lab.shape
    blocks = lab.reshape(h // k, k, w // k, k).transpose(0, 2, 1, 3).reshape(h // k, w // k, k * k)
    counts = np.stack([(blocks == i).sum(axis=2) for i in range(n)], axis=2)
    return np.argmax(counts, axis=2).astype(np.int16)


def coarsen(ctx: Context, k: int) -> Context:
    """The context box-filtered by k (grading an image k times smaller than the grade resolution).

    References and mutants keep stratified variances (their renders sampled
    every fine pixel); the noise model gets the unstratified per-sample
    variance of a coarse pixel, mean_j(var_j) + var_j(mean_j), because the
    student sampled the coarse pixel as a whole.
    """
    if k == 1:
        return ctx
    def coarse_var(cam, v):
        m = (ctx.baseline.mean if cam == ctx.assignment.camera else ctx.references[cam].mean).astype(np.float64)
        between = block_means(m * m, k) - block_means(m, k) ** 2
        return (block_means(v.astype(np.float64), k) + np.maximum(between, 0)).astype(np.float32)

    return replace(
        ctx,
        references={c: _coarse_expected(e, k) for c, e in ctx.references.items()},
        model_var={cam: coarse_var(cam, v) for cam, v in ctx.model_var.items()},
        unsampled=None if ctx.unsampled is None else _coarse_expected(ctx.unsampled, k),
        model_var_unsampled={cam: coarse_var(cam, v) for cam, v in ctx.model_var_unsampled.items()},
        baseline=_coarse_expected(ctx.baseline, k),
        mutants={m: _coarse_expected(e, k) for m, e in ctx.mutants.items()},
        direct_fraction={c: block_means(d.astype(np.float64), k).astype(np.float32) for c, d in ctx.direct_fraction.items()},
        labels={c: _mode_blocks(lab, k, len(ctx.label_names)) for c, lab in ctx.labels.items()},
        explain=None,  # the variations exist at the grade resolution only
    )
