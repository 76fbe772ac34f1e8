"""The suite's computation: every scene rendered, tested by mcrt and by Mitsuba's rule, perturbed, timed.

:func:`run_case` does one scene, :func:`run_suite` all of them (the tuning
part first, the held-out part last) and the summary. Everything returned is
JSON-ready.
"""

from __future__ import annotations

import math
import time
from typing import IO, Callable

import numpy as np

from mcrt.msuite.perturb import ISSUE, PERTURBATIONS, perturbed
from mcrt.msuite.scenes import Case, find_cases
from mcrt.msuite.zrule import z_rule

#: Mitsuba's render-test budget: 2e6 samples over the image.
SAMPLE_BUDGET = 2_000_000
#: The references do not record their spp; Mitsuba's reference generator renders 32000 by default.
REFERENCE_SPP = 32000
#: The largest noiseless difference the suite accepts as a reference's offset (rounding of an old colour
#: conversion is 0.03 to 0.1 %); a larger one is a difference, reported as such.
MAX_OFFSET = 0.005
#: Seeds of the correct renders (base + k) and of the perturbed ones (base + index).
CORRECT_SEED, PERTURBED_SEED = 1000, 2000
#: Levels (beside each scene's own) at which the report counts rejected correct renders, from their family p-values.
CALIBRATION_LEVELS = (0.001, 0.01, 0.05)
#: The white of the references older Mitsuba versions wrote, as stored: bsdf_spheres/refs/test_constant_ref_rgb.exr
#: (Mitsuba 2.2.1) holds the constant emitter's radiance 1.0 in its background pixel [0, 0] as this RGB.
#: :func:`xyz_version_rtol` turns it into the margin against such references, per tested (XYZ) channel.
STORED_WHITE_RGB = (1.001084, 0.999708, 0.999703)
#: An absolute margin of every test against a reference: twice float32's spacing at 1.0 (2^-22, about 2.4e-7).
#: Mitsuba computes in float32 with factors of order 1 (filter weights, reflectances, colour conversion), so a
#: reference value near 0 carries rounding at that scale, not at its own: the report counts, per reference, the
#: XYZ values of its dark pixels that lie on the 2^-24 grid (:func:`rounding_grid`).
ROUNDING_ATOL = 2.0 * float(np.finfo(np.float32).eps)
#: Dark pixel-channels, for :func:`rounding_grid`: a reference XYZ value this small in magnitude (but not 0).
DARK = 1e-5


def budget_spp(h: int, w: int, scale: float = 1.0) -> int:
    """Mitsuba's spp for an h x w image, 2e6 // pixels, times ``scale`` (at least 2)."""
    return max(2, int(SAMPLE_BUDGET * scale) // (h * w))


def _round_up(x: float) -> float:
    """A tolerance just above ``x``, two significant digits (0.001084 -> 0.0011)."""
    if x <= 0:
        return 0.0
    e = math.floor(math.log10(x)) - 1
    return float(f"{math.ceil(x / 10**e) * 10**e:.2g}")  # 28 * 1e-5 printed as 0.00028, not 0.00028000000000000003


def xyz_version_rtol(white=STORED_WHITE_RGB) -> tuple[float, float, float]:
    """The margin against a reference another Mitsuba version wrote, per XYZ channel (the space of the tests).

    That version's colour conversion stores a white 1.0 as ``white`` (RGB).
    Through :data:`mcrt.image_files.RGB_TO_XYZ` its relative offset from a
    true white, channel by channel, rounded up to two significant digits, is
    the margin of that channel; :data:`EXACT_RTOL` (float32 rounding) where
    the offset is below it (Y, the luminance row, nearly cancels).
    """
    from mcrt.image_files import RGB_TO_XYZ
    from mcrt.stats.twosample import EXACT_RTOL

    stored, true = RGB_TO_XYZ @ np.asarray(white, np.float64), RGB_TO_XYZ @ np.ones(3)
    return tuple(max(EXACT_RTOL, _round_up(abs(o))) for o in stored / true - 1.0)


def rtol_text(rtol) -> str:
    """A margin in words: one number, or one per channel (``X 0.00031, Y exact, Z 0.00028``)."""
    from mcrt.stats.twosample import EXACT_RTOL

    values = np.atleast_1d(np.asarray(rtol, np.float64))
    if np.all(values == values[0]):
        return f"{values[0]:g}"
    return ", ".join(f"{c} {'exact' if v <= EXACT_RTOL else f'{v:g}'}" for c, v in zip("XYZ", values))


def rounding_grid(ref_xyz: np.ndarray) -> dict:
    """How many of the reference's dark XYZ values (0 < |v| < :data:`DARK`) lie on multiples of 2^-24 (within 1 %
    of a step): ``{'dark', 'on_grid'}``. Values that all do were rounded at the scale of 1, not at their own."""
    v = np.asarray(ref_xyz, np.float64).ravel()
    v = v[(v != 0) & (np.abs(v) < DARK)]
    k = v / 2.0**-24
    return {"dark": int(v.size), "on_grid": int(np.count_nonzero(np.abs(k - np.round(k)) < 0.01))}


def _test(render, ref, ref_var_raw, *, alpha: float, tiles, rtol) -> dict:
    from mcrt.stats import compare_multiscale

    ms = compare_multiscale(render, ref, tiles=tiles, alpha=alpha, policy="reference-floor", channels="xyz", rtol=rtol,
                            atol=ROUNDING_ATOL)
    z = z_rule(render.mean, ref.mean, ref_var_raw, render.spp)
    failing = []
    for t, c, rej in zip(ms.tiles, ms.comparisons, ms.rejected):
        for ty, tx, ch in np.argwhere(rej)[:10]:
            y0, y1, x0, x1 = c.tile_box(int(ty), int(tx))
            failing.append({"tile": t, "rows": [y0, y1 - 1], "cols": [x0, x1 - 1], "channel": "XYZ"[ch],
                            "t": float(c.t[ty, tx, ch]) if np.isfinite(c.t[ty, tx, ch]) else None,
                            "rel_diff": float(c.rel_diff[ty, tx, ch]), "noiseless": bool(c.deterministic[ty, tx, ch]),
                            "mean": float(c.mean_a[ty, tx, ch]), "reference": float(c.mean_b[ty, tx, ch])})
    masks = [r.copy() for r in ms.rejected]
    # The family's p-value: the smallest level at which weighted Holm rejects any test (its smallest adjusted
    # p-value), so one render is judged at every level at once (the false-alarm rate at any level, from the same renders).
    p_family = float(min((float(pa.min()) for pa in ms.p_adjusted if pa.size), default=1.0))
    return {"_masks": masks, "_t": [np.nan_to_num(c.t, nan=0.0, posinf=50.0, neginf=-50.0) for c in ms.comparisons], "mcrt": {"p_family": p_family, "failing": failing[:10], "peak": float(np.abs(ref.mean).max()), "passed": ms.passed, "rejected": ms.n_rejected, "noiseless_rejected": ms.noiseless_rejected,
                     "noisy_rejected": ms.noisy_rejected, "tests": ms.n_tests, "by_scale": ms.by_scale(),
                     "largest_noiseless_difference": ms.largest_noiseless_difference(), "headline": ms.headline()},
            "mitsuba": z}


def run_case(case: Case, *, spp_scale: float = 1.0, seeds: int = 1, alpha: float = 0.01, tiles=(2, 4, 8, 16, 32, 0),
             ref_spp: int = REFERENCE_SPP, perturbations=tuple(PERTURBATIONS), backend: str = "llvm",
             version_rtol: float | None = None) -> dict:
    """One scene: ``seeds`` correct renders and the perturbed ones, each tested both ways.

    A reference that another Mitsuba version wrote is compared within
    ``version_rtol`` (a margin of every test; None: per XYZ channel,
    :func:`xyz_version_rtol`, from the white such versions store). Every test
    also accepts an absolute difference up to :data:`ROUNDING_ATOL`
    (float32 rounding at the scale of 1). The reference
    offset: where the first correct render still differs from the
    reference in noiseless tiles (no noise there: a difference of the
    reference, such as a constant 1.0 stored as 1.00108) of at most
    :data:`MAX_OFFSET`, that difference,
    rounded up, becomes the scene's ``rtol`` (a margin of every test,
    :func:`mcrt.stats.compare_images`), stated in the verdict, and every
    test of the scene uses it, as a user would with ``mcrt compare --rtol``.
    """
    import mitsuba as mi

    from mcrt import mitsuba_scene as mm
    from mcrt.image_files import RGB_TO_XYZ, read_exr, read_mitsuba_reference
    from mcrt.stats.twosample import EXACT_RTOL

    mm._use(backend)
    t0 = time.perf_counter()
    scene, notes = mm.load_scene_file(case.xml)
    ref = read_mitsuba_reference(case.ref, case.ref_var, spp=ref_spp, space="xyz")
    ref_var_raw = read_exr(case.ref_var).mean.astype(np.float64) @ RGB_TO_XYZ.T  # as Mitsuba's test reads it
    h, w = ref.mean.shape[:2]
    spp = budget_spp(h, w, spp_scale)
    depth = mm.integrator_max_depth(scene.integrator())
    out = {"name": case.name, "held_out": case.held_out, "alpha": alpha, "size": [w, h], "spp": spp, "integrator": None,
           "max_depth": depth, "notes": notes, "ref_variance": ref.extra["variance"], "correct": [],
           "perturbations": {}}

    def render(seed, max_depth=None):
        r = mm.render_with_variance(scene, spp=spp, seed=seed, space="xyz", max_depth=max_depth, backend=backend)
        if r.mean.shape != ref.mean.shape:
            raise ValueError(f"{case.name}: renders {r.mean.shape[1]}x{r.mean.shape[0]}, its reference is {w}x{h}")
        return r

    # A reference written by another Mitsuba version went through that version's colour conversion, which offsets
    # a white (STORED_WHITE_RGB) in every pixel, noisy or not; in XYZ, the space of the tests, the offset differs
    # per channel, hence a margin per channel.
    written_by = ref.extra.get("exr.generatedBy", "")
    other_version = written_by != f"Mitsuba version {mi.__version__}"
    margin = xyz_version_rtol() if version_rtol is None else (max(EXACT_RTOL, version_rtol),) * 3
    rtol = tuple(margin) if other_version else (EXACT_RTOL,) * 3
    out["written_by"], out["version_rtol"] = written_by, list(rtol)
    out["rounding_grid"] = rounding_grid(ref.mean)
    masks, ts = [], []
    render_sum = np.zeros(ref.mean.shape)
    for k in range(seeds):
        r = render(CORRECT_SEED + k)
        render_sum += r.mean
        out["integrator"], out["method"] = r.renderer, r.extra.get("method")
        out["variance_method"] = r.extra.get("variance_method")
        res = _test(r, ref, ref_var_raw, alpha=alpha, tiles=tiles, rtol=rtol)
        # A wider rtol makes more low-noise pixels noiseless (their noise must stay below it): repeat, a few times.
        for _ in range(3):
            offset = res["mcrt"]["largest_noiseless_difference"]
            if k or not res["mcrt"]["noiseless_rejected"] or offset > MAX_OFFSET:
                break
            rtol = tuple(max(x, _round_up(offset)) for x in rtol)
            out["reference_offset"] = offset
            res = _test(r, ref, ref_var_raw, alpha=alpha, tiles=tiles, rtol=rtol)
        res.update(seed=CORRECT_SEED + k, time=r.wall_time, spp=r.spp)
        if k == 0:
            base_masks = res["_masks"]
        masks.append(res.pop("_masks"))
        ts.append(res.pop("_t"))
        if k and res["mcrt"]["passed"]:  # a passing repeat: its verdict and p-value are all the report reads
            res["mcrt"] = {key: res["mcrt"][key] for key in ("p_family", "passed", "rejected")}
        out["correct"].append(res)
    out["rtol"] = list(rtol)
    confirm(out["correct"], masks, ts)
    out["objects"], out["emitters"] = scene_objects(scene), sorted({e.class_name() for e in scene.emitters()})
    rejected = [res for res in out["correct"] if not res["mcrt"]["passed"]]
    if rejected:  # where the renders differ: the seeds' mean render against the reference, and what is seen there
        out["differences"] = describe_differences(scene, rejected[0]["mcrt"]["failing"], render_sum / seeds, ref.mean)
    first = out["correct"][0]
    for i, name in enumerate(perturbations):
        with perturbed(mi, scene, name, depth) as change:
            if change is None:
                out["perturbations"][name] = None
                continue
            what, new_depth = change
            r = render(PERTURBED_SEED + i, new_depth)
        res = _test(r, ref, ref_var_raw, alpha=alpha, tiles=tiles, rtol=rtol)
        res.update(change=what, time=r.wall_time)
        # Caught: the test rejects on evidence the correct render does not show. mcrt: a rejected test (tile,
        # channel, scale) that the first correct render does not have; Mitsuba's rule: failing where the correct
        # render passes, or more failing pixel-channels than the correct render's plus the rule's allowance.
        res.pop("_t")
        new = sum(int(np.count_nonzero(m & ~b)) for m, b in zip(res.pop("_masks"), base_masks))
        res["mcrt"]["new_rejections"] = new
        res["mcrt"]["caught"] = new > 0
        z0, z1 = first["mitsuba"], res["mitsuba"]
        res["mitsuba"]["caught"] = bool(not z1["passed"] and (z0["passed"] or z1["failing"] > z0["failing"] + z1["allowed"]))
        out["perturbations"][name] = res
    out["time"] = time.perf_counter() - t0
    return out


def _bsdf_text(bsdf) -> str:
    """A BSDF as its chain of classes and the files of its textures (``Mask / TwoSided / SmoothDiffuse (leaf_mask.png)``)."""
    import re

    text = str(bsdf)
    classes = [c for c in re.findall(r"(\w+)\[", text) if not re.search("Texture|Spectrum|Transform|Bounding|brdf", c)]
    files = list(dict.fromkeys(re.findall(r'name = "([^"]+)"', text)))
    return " / ".join(dict.fromkeys(classes)) + (f" ({', '.join(files)})" if files else "")


def _shape_text(shape) -> str:
    """A shape as its file (or class), where it is (its bounding box's centre) and its BSDF."""
    import re

    found = re.search(r'name = "([^"]+)"', str(shape).split("bsdf =")[0])
    c = np.array(shape.bbox().center(), np.float64).ravel()
    where = ", ".join(f"{v:g}" for v in np.round(c, 2))
    return f"{found.group(1) if found else shape.class_name()} at ({where}) with {_bsdf_text(shape.bsdf())}"


def scene_objects(scene) -> list[str]:
    """Every shape of the scene in words (:func:`_shape_text`), sorted."""
    return sorted(_shape_text(s) for s in scene.shapes())


def seen_in(scene, box, per_pixel: int = 4) -> list[tuple[str, float]]:
    """What the camera sees in a pixel box ``(y0, y1, x0, x1)``, end exclusive: ``(shape in words, fraction)`` for
    each shape its primary rays (``per_pixel`` x ``per_pixel`` per pixel) hit first, largest first, and
    ``('nothing', fraction)`` for those that hit nothing. A shape with an opacity mask counts over its whole surface."""
    import drjit as dr
    import mitsuba as mi

    y0, y1, x0, x1 = box
    sensor = scene.sensors()[0]
    w, h = sensor.film().crop_size()
    ys, xs = np.meshgrid((np.arange(y0 * per_pixel, y1 * per_pixel) + 0.5) / per_pixel,
                         (np.arange(x0 * per_pixel, x1 * per_pixel) + 0.5) / per_pixel, indexing="ij")
    ray, _ = sensor.sample_ray(0.0, 0.0, mi.Point2f(xs.ravel() / w, ys.ravel() / h), mi.Point2f(0.5, 0.5))
    si = scene.ray_intersect(ray)
    hit = np.array(si.is_valid(), bool)
    ids = np.array(dr.reinterpret_array(mi.UInt32, si.shape))
    out = []
    for s in scene.shapes():
        n = np.count_nonzero(hit & (ids == np.array(dr.reinterpret_array(mi.UInt32, mi.ShapePtr(s)))[0]))
        if n:
            out.append((_shape_text(s), n / hit.size))
    out.sort(key=lambda x: -x[1])
    if not hit.all():
        out.append(("nothing", float(1.0 - hit.mean())))
    return out


def describe_differences(scene, failing: list[dict], mean_render: np.ndarray, ref: np.ndarray, limit: int = 3) -> list[dict]:
    """Each pixel box of ``failing`` (a rejected render's tests; at most ``limit`` boxes): the relative difference
    of ``mean_render`` (the mean of every seed's render) from the reference there, per channel, their means, and
    what the camera sees there (:func:`seen_in`)."""
    boxes = list(dict.fromkeys((f["rows"][0], f["rows"][1] + 1, f["cols"][0], f["cols"][1] + 1) for f in failing))
    out = []
    for y0, y1, x0, x1 in boxes[:limit]:
        a = mean_render[y0:y1, x0:x1].mean(axis=(0, 1))
        b = ref[y0:y1, x0:x1].astype(np.float64).mean(axis=(0, 1))
        with np.errstate(divide="ignore", invalid="ignore"):
            rel = np.where(b != 0, a / b - 1.0, 0.0)
        noiseless = all(f["noiseless"] for f in failing if (f["rows"][0], f["cols"][0]) == (y0, x0))
        out.append({"rows": [y0, y1 - 1], "cols": [x0, x1 - 1], "rel_diff": [float(v) for v in rel], "noiseless": noiseless,
                    "mean": [float(v) for v in a], "reference": [float(v) for v in b],
                    "seen": [[what, float(f)] for what, f in seen_in(scene, (y0, y1, x0, x1))]})
    return out


def confirm(correct: list[dict], masks: list, ts: list, alpha: float = 0.01) -> None:
    r"""Say of each rejected correct render whether the other seeds confirm its rejected tests (in place).

    A rejected test (tile, channel, scale) of one seed is confirmed when the
    same test on the other seeds' renders (independent of the seed that
    picked it, so no selection bias) leans the same way: Stouffer's
    :math:`z = \sum_j t_j / \sqrt{k}` over the k other seeds beyond the
    one-sided normal quantile at ``alpha`` over that render's rejected tests
    (Bonferroni). A confirmed rejection is a difference of the reference
    too small to be rejected on every seed; an unconfirmed one is a false
    alarm. Sets ``mcrt['confirmed']`` (None where not rejected or without
    another seed) and ``mcrt['confirm_z']``.
    """
    from scipy import stats as sps

    for i, res in enumerate(correct):
        res["mcrt"]["confirmed"], res["mcrt"]["confirm_z"] = None, None
        others = [j for j in range(len(correct)) if j != i]
        if res["mcrt"]["passed"] or not others:
            continue
        tests = [(s, tuple(idx)) for s, m in enumerate(masks[i]) for idx in np.argwhere(m)]
        crit = sps.norm.isf(alpha / len(tests))
        best = 0.0
        for s, idx in tests:
            sign = np.sign(ts[i][s][idx])
            z = sign * sum(ts[j][s][idx] for j in others) / np.sqrt(len(others))
            best = max(best, float(z))
        res["mcrt"]["confirmed"], res["mcrt"]["confirm_z"] = bool(best >= crit), best


def verdict(case: dict) -> str:
    """mcrt's verdict on the scene's first correct render, in words."""
    m = case["correct"][0]["mcrt"]
    if not m["passed"]:
        return (f"DIFFERENT: {m['noisy_rejected']} noisy and {m['noiseless_rejected']} noiseless tests rejected "
                f"({', '.join(f'{k} {v}' for k, v in m['by_scale'].items())})")
    if "reference_offset" in case:
        return (f"consistent, with the reference's offset in noiseless pixels ({100 * case['reference_offset']:.3g} %) "
                f"accepted (rtol {rtol_text(case['rtol'])})")
    if max(np.atleast_1d(case.get("rtol", 0))) > 1e-5:
        return f"consistent (rtol {rtol_text(case['rtol'])}: a reference of {case['written_by'] or 'another version'})"
    return "consistent"


def _false_alarms(cases: list[dict], who: str) -> tuple[list[bool], list[list[bool]]]:
    """Per scene, whether its rejections show a difference of the reference; per render, whether it is a false alarm.

    A scene whose every correct render (independent seeds, more than one) is
    rejected shows a difference of its reference, not noise; so does one
    with a rejection the other seeds confirm (:func:`confirm`). Other
    rejections are false alarms.
    """
    rejected = [[not r[who]["passed"] for r in c["correct"]] for c in cases]
    confirmed = [[bool(r[who].get("confirmed")) for r in c["correct"]] for c in cases]
    everywhere = [all(x) and len(x) > 1 for x in rejected]
    systematic = [ev or any(cf) for ev, cf in zip(everywhere, confirmed)]
    false = [[xj and not ev and not cj for xj, cj in zip(x, cf)] for x, ev, cf in zip(rejected, everywhere, confirmed)]
    return systematic, false


def _calibration(cases: list[dict], systematic: list[bool]) -> dict:
    """mcrt's rejection rate of correct renders at several levels, from the same renders (scenes with a difference
    of the reference left out): a render whose family p-value is at or below a level is rejected at that level."""
    ps = [r["mcrt"]["p_family"] for c, sy in zip(cases, systematic) if not sy for r in c["correct"]]
    levels = sorted({*(c["alpha"] for c in cases), *CALIBRATION_LEVELS})
    return {"renders": len(ps), "rejected": {f"{a:.3g}": sum(p <= a for p in ps) for a in levels}}


def _caught(cases: list[dict], names) -> dict:
    """``{'applicable', 'mcrt', 'mitsuba'}``: the perturbed renders among ``names`` and how many each test catches."""
    applicable = [p for c in cases for name, p in c["perturbations"].items() if name in names and p is not None]
    return {"applicable": len(applicable), **{who: sum(p[who]["caught"] for p in applicable) for who in ("mcrt", "mitsuba")}}


def summarize(cases: list[dict]) -> dict:
    """Counts over ``cases``: rejected correct renders (differences of the reference and false alarms, :func:`_false_alarms`),
    the rejection rate at other levels, suite runs (one seed over every scene) with a false alarm, and catches of
    the perturbations by both tests (over all, the issue's four, and each perturbation) on the scenes without a
    difference of the reference."""
    s = {"scenes": len(cases), "correct_renders": sum(len(c["correct"]) for c in cases)}
    seeds = max((len(c["correct"]) for c in cases), default=0)
    for who in ("mcrt", "mitsuba"):
        systematic, false = _false_alarms(cases, who)
        s[f"{who}_rejected_correct"] = sum(not r[who]["passed"] for c in cases for r in c["correct"])
        s[f"{who}_reference_differences"] = sum(systematic)
        s[f"{who}_false_alarms"] = sum(map(sum, false))
        # One suite run is one seed over every scene: a false alarm in any scene fails the CI check.
        s[f"{who}_suite_runs_failed"] = sum(any(f[k] for f in false if k < len(f)) for k in range(seeds))
        if who == "mcrt":
            s["mcrt_calibration"] = _calibration(cases, systematic)
    s["suite_runs"] = seeds
    # Power only where mcrt finds the correct renders consistent: where it already rejects them (a difference of
    # the reference), a perturbed render's rejections are not evidence of the perturbation.
    systematic, _ = _false_alarms(cases, "mcrt")
    s["power_left_out"] = [c["name"] for c, sy in zip(cases, systematic) if sy]
    fair = [c for c, sy in zip(cases, systematic) if not sy]
    names = {name for c in fair for name in c["perturbations"]}
    total = _caught(fair, names)
    s["perturbations"], s["mcrt_caught"], s["mitsuba_caught"] = total["applicable"], total["mcrt"], total["mitsuba"]
    s["issue_sizes"] = _caught(fair, ISSUE)
    s["by_perturbation"] = {name: _caught(fair, {name}) for name in PERTURBATIONS if name in names}
    s["reference_offsets"] = sum("reference_offset" in c for c in cases)
    return s


def run_suite(folder, *, only=(), held_out: str = "include", alpha: float = 0.01, log: IO[str] | None = None,
              on_case: Callable[[dict], None] | None = None, **options) -> dict:
    """Every scene of ``folder`` (:func:`find_cases`), tuning part first, held-out part last.

    ``alpha`` is the family-wise error rate of the whole suite, run as one
    check: each scene's comparisons are at ``alpha / scenes run``
    (Bonferroni over the scenes; within a scene the tiles, channels and
    scales are in one weighted-Holm family), so a correct suite fails one
    seed's run with probability at most ``alpha``.
    ``held_out``: ``'include'``, ``'exclude'`` or ``'only'``. ``options``
    go to :func:`run_case`. Progress (done, time left) goes to ``log``;
    ``on_case`` is called with each scene's result as it is done.
    """
    cases, skipped = find_cases(folder)
    if only:
        unknown = set(only) - {c.name for c in cases}
        if unknown:
            raise ValueError(f"no scene {sorted(unknown)[0]!r} with references in {folder}")
        cases = [c for c in cases if c.name in only]
    if held_out == "exclude":
        cases = [c for c in cases if not c.held_out]
    elif held_out == "only":
        cases = [c for c in cases if c.held_out]
    cases = sorted(cases, key=lambda c: (c.held_out, c.name))
    scene_alpha = alpha / max(1, len(cases))
    results, t0 = [], time.perf_counter()
    for k, case in enumerate(cases):
        try:
            r = run_case(case, alpha=scene_alpha, **options)
        except (ValueError, RuntimeError) as e:  # one broken scene never stops the suite
            r = {"name": case.name, "held_out": case.held_out, "error": " ".join(str(e).split())}
        results.append(r)
        if on_case is not None:
            on_case(r)
        if log is not None:
            el = time.perf_counter() - t0
            left = el / (k + 1) * (len(cases) - k - 1)
            what = r.get("error") or f"{verdict(r)}; Mitsuba's rule {'passes' if r['correct'][0]['mitsuba']['passed'] else 'FAILS'}"
            print(f"[{k + 1}/{len(cases)}] {case.name}: {what} ({r.get('time', 0):.1f} s; {el:.0f} s, ~{left:.0f} s left)",
                  file=log, flush=True)
    done = [r for r in results if "error" not in r]
    given = options.get("version_rtol")
    margins = {"stored_white_rgb": list(STORED_WHITE_RGB), "rounding_atol": ROUNDING_ATOL,
               "version_rtol": list(xyz_version_rtol()) if given is None else [given] * 3}
    return {"alpha": alpha, "scene_alpha": scene_alpha, "margins": margins, "cases": results, "skipped": [{"name": n, "why": w} for n, w in skipped],
            "summary": {"all": summarize(done), "tuning": summarize([r for r in done if not r["held_out"]]),
                        "held_out": summarize([r for r in done if r["held_out"]])},
            "errors": [{"name": r["name"], "error": r["error"]} for r in results if "error" in r]}
