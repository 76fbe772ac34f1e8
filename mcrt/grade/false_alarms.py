"""How often the grader takes points from a correct render: ``mcrt grade-false-alarms``.

Correct renders of the course scene from several estimators and samplers
(mcrt; Mitsuba's ``path`` with its ``independent``, ``stratified``,
``ldsampler`` and ``multijitter`` samplers, ``volpath``; mcrt and Mitsuba's
``path`` with Russian roulette from the first bounce, less efficient than
mcrt's default; mcrt and Mitsuba's ``prb_basic`` without light sampling,
far noisier, which the noise criterion knows by the shape of its noise), at 16 to 1024
spp, at hand-in resolutions from 64x64 (graded at 64x64) to 800x800 (graded
at 100x100), as float images and as 8-bit PNGs in the common encodings, are
graded with the course's rubric. A *false alarm* is any point lost on a
criterion that judges the rendering (everything but ``resolution``, which a
hand-in at another resolution loses by design). The report gives the rate
overall and per group, the raw p-values of each structured-error
detector (:mod:`mcrt.grade.structure`) and of the per-object tests
(:mod:`mcrt.grade.objects`), whose share of those at or below
0.01 should be near 0.01 (or below, for the conservative pixel bound), and
the noise criterion's variance ratios (hand-in over mcrt at the declared
spp): the spread that the rubric's ``noise.max_ratio`` must clear, and the
shape of each render's noise (:func:`mcrt.grade.stages.noise.unsampled_shape`)
on either side of the bound that tells a tracer without light sampling.

Seeds are fixed (case k of a group uses seed ``base + k``), so the report is
reproducible bit for bit on one machine. Mitsuba renders are the slow part
(about a minute per 800x800 image at 16 spp on two cores).
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from mcrt.exitcodes import EXIT_FAILED, EXIT_OK

COMMAND = "grade-false-alarms --out reports/grading/false_alarms"


@dataclass(frozen=True)
class Case:
    # "mcrt", or "path/<sampler>", "volpath/<sampler>", "prb_basic/<sampler>" (Mitsuba); "-rr1": Russian roulette from
    # the first bounce; "mcrt-none": mcrt without light sampling
    renderer: str
    spp: int
    res: int  # hand-in width = height
    grade: int  # grade width = height
    seed: int
    file: str = "float"  # "float", or "png-srgb", "png-gamma2.2", "png-gamma2" (8-bit, Pillow)

    @property
    def group(self) -> str:
        return f"{self.res}->{self.grade}"

    @property
    def name(self) -> str:
        return f"{self.renderer.replace('/', '-')}_{self.spp}spp_{self.res}px_{self.file}_s{self.seed}"


MITSUBA = ("path/independent", "path/stratified", "path/ldsampler", "path/multijitter", "volpath/independent")
RR1 = ("mcrt-rr1", "path-rr1/independent")
#: Correct estimators without light sampling (the light found by bouncing into it).
UNSAMPLED = ("mcrt-none", "prb_basic/independent")


def cases(seeds: int = 3) -> list[Case]:
    """The study's renders (module docstring); ``seeds`` per setting at 64x64, fewer where renders are slow."""
    out, seed = [], 7000
    for r in ("mcrt",) + MITSUBA:  # 64x64 hand-ins graded at 64x64: every spp
        for spp in (16, 64, 256, 1024):
            for _ in range(seeds):
                out.append(Case(r, spp, 64, 64, seed := seed + 1))
    for r in ("mcrt",) + MITSUBA:  # 100x100 graded at 100x100
        for spp in ((16, 64, 256, 1024) if r == "mcrt" else (16, 64, 256)):
            for _ in range(max(1, seeds - 1)):
                out.append(Case(r, spp, 100, 100, seed := seed + 1))
    for res in (200, 400):  # box-filtered by 2 and 4
        for spp in (16, 256):
            out.append(Case("mcrt", spp, res, 100, seed := seed + 1))
        out.append(Case("path/independent", 16, res, 100, seed := seed + 1))
    for spp in (16, 64, 256):  # the course's own 800x800, box-filtered by 8
        for _ in range(max(1, seeds - 1)):
            out.append(Case("mcrt", spp, 800, 100, seed := seed + 1))
    for r in ("path/independent", "path/ldsampler", "path/stratified"):
        out.append(Case(r, 16, 800, 100, seed := seed + 1))
    for f in ("png-srgb", "png-gamma2.2", "png-gamma2"):  # 8-bit files
        for spp, res, grade in ((64, 64, 64), (256, 64, 64), (100, 100, 100), (16, 800, 100)):
            out.append(Case("mcrt", spp, res, grade, seed := seed + 1, f))
    for r in RR1:  # less efficient estimators: Russian roulette from the first bounce (noisier than mcrt's default)
        for spp in (16, 64, 256, 1024):
            for _ in range(max(1, seeds - 1)):
                out.append(Case(r, spp, 64, 64, seed := seed + 1))
    for r in UNSAMPLED:
        for spp in (16, 64, 256, 1024):
            for _ in range(max(1, seeds - 1)):
                out.append(Case(r, spp, 64, 64, seed := seed + 1))
    return out


def render_case(scene, c: Case) -> np.ndarray:
    """The case's image, (res, res, 3) float64 linear radiance."""
    rr_depth = 1 if "-rr1" in c.renderer else None
    if c.renderer.startswith("mcrt"):
        from mcrt.render import render

        s = scene.settings(camera="near", width=c.res, height=c.res, spp=c.spp, max_depth=8, rr_depth=rr_depth)
        tricks = {"light_sampling": "none"} if c.renderer == "mcrt-none" else {}
        return render(scene, s, seed=c.seed, progress=False, **tricks).mean.astype(np.float64)
    from mcrt.mitsuba_scene import render_with_variance, scene_dict

    integrator, sampler = c.renderer.split("/")
    d = scene_dict(scene, "near", c.res, c.res, 8, integrator=integrator.removesuffix("-rr1"),
                   **({"rr_depth": rr_depth} if rr_depth else {}))
    d["sensor"] = dict(d["sensor"], sampler={"type": sampler, "sample_count": c.spp})
    # One pass of all samples: the stratified and low-discrepancy samplers lay out a pixel's samples per pass.
    per_pass = c.spp if c.res * c.res * c.spp < 2**31 else None
    return render_with_variance(d, spp=c.spp, seed=c.seed, spp_per_pass=per_pass).mean.astype(np.float64)


def _encode(img: np.ndarray, curve: str) -> np.ndarray:
    from mcrt.image_files import srgb_oetf

    enc = {"srgb": srgb_oetf, "gamma2.2": lambda x: x ** (1 / 2.2), "gamma2": np.sqrt}[curve]
    return np.round(255 * enc(np.clip(img, 0.0, 1.0))).astype(np.uint8)


def grade_case(c: Case, img: np.ndarray, ctx, tmp: Path):
    """Grade one case's image as a student would hand it in (a float image in memory, or a PNG file and manifest)."""
    from mcrt.grade.grader import grade_image, grade_submission
    from mcrt.grade.submissions import discover

    if c.file == "float":
        return grade_image(c.name, ctx, [img], spp=c.spp)
    from PIL import Image

    d = tmp / c.name
    d.mkdir(parents=True)
    Image.fromarray(_encode(img, c.file.split("-", 1)[1]), "RGB").save(d / "render.png")
    (d / "manifest.toml").write_text(f"spp = {c.spp}\n")
    return grade_submission(discover(d, single=True, student=c.name)[0], ctx)


def _assignment(res: int, grade: int):
    """The course's rubric (course2023 at 64x64, course2023_800 at 100x100) for res x res hand-ins."""
    from mcrt.grade.assignment import assignment_from_dict, load_assignment
    from mcrt.scene import DATA_DIR

    root = DATA_DIR / "assignments"
    base = load_assignment(root / ("course2023.toml" if grade == 64 else "course2023_800.toml"))
    data = {"name": f"{base.name}-{res}", "scene": {"file": base.scene_file, "camera": base.camera, "width": res,
                                                    "height": res, "max_depth": base.max_depth, "spp": base.spp,
                                                    "min_spp": base.min_spp},
            "grading": {"grade_width": grade, "grade_height": grade, "tiles": list(base.tiles)}}
    return assignment_from_dict(data, base.path, base=root)


def _false_alarm(r) -> list[str]:
    return [t.name for t in r.tests if t.score < t.max_score and t.name != "resolution"]


def run_study(out: Path, *, seeds: int, cache: str | None, progress: bool = True) -> dict:
    """Render and grade every case; write ``out``/false_alarms.json and index.md; return the JSON's content."""
    from mcrt.film import Progress
    from mcrt.grade.expected import prepare_context
    from mcrt.scene import load_scene

    scene = load_scene()
    todo = cases(seeds)
    contexts: dict[tuple[int, int], object] = {}
    rows = []
    bar = Progress(len(todo), label="false alarms", unit="renders", enabled=progress)
    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="mcrt-fa-") as tmp:
        for k, c in enumerate(todo):
            if (c.res, c.grade) not in contexts:
                contexts[(c.res, c.grade)] = prepare_context(_assignment(c.res, c.grade), cache)
            img = render_case(scene, c)
            r = grade_case(c, img, contexts[(c.res, c.grade)], Path(tmp))
            st = r.details.get("structure", {})
            reg = st.get("registration") or {}
            nz = r.details.get("noise") or {}
            eff = nz.get("spp_effective")
            rows.append({**c.__dict__, "group": c.group, "score": r.score, "max_score": r.max_score,
                         "lost": _false_alarm(r), "p_registration": reg.get("p"), "p_blur": st.get("p_blur"),
                         "p_correlation": st.get("p_correlation"), "p_objects": st.get("p_objects"),
                         "p_objects_relevant": st.get("p_objects_relevant"),
                         "p_object_structure": st.get("p_object_structure"), "objects_rel": st.get("objects_rel"),
                         "p_patches": st.get("p_patches"),
                         "penalised": st.get("penalised"),
                         "var_ratio": c.spp / eff if eff else None, "unsampled_shape": nz.get("unsampled_shape"),
                         "unsampled_body": nz.get("unsampled_body"),
                         "unsampled": bool(nz.get("unsampled")),
                         "p_repeats": (nz.get("repeats") or {}).get("p"),
                         "encoding": (r.details.get("encoding") or {}).get("detected")})
            bar.update(k + 1)
    th = next(iter(contexts.values())).assignment.thresholds
    max_ratio = th.max_noise_ratio
    summary = summarise(rows, max_ratio)
    data = {"command": f"mcrt {COMMAND}" + (f" --seeds {seeds}" if seeds != 3 else ""), "seeds": seeds,
            "wall_time_s": time.perf_counter() - t0, "min_effect": th.min_effect, "summary": summary, "cases": rows}
    out.mkdir(parents=True, exist_ok=True)
    (out / "false_alarms.json").write_text(json.dumps(data, indent=1) + "\n")
    (out / "index.md").write_text(markdown(data))
    return data


#: The detectors whose raw p-values the report counts: one per render, or one per object and channel.
DETECTORS = {"registration": "registration", "blur": "blur", "correlation": "correlation",
             "objects": "objects: zero difference (per object and channel)",
             "objects_relevant": "objects: difference beyond min_effect (the test that is scored)",
             "object_structure": "object structure (per object)",
             "patches": "patches of pixels off together (brighter, darker)",
             "repeats": "noise repeating between pixels apart (mcrt/grade/copytest.py; Bonferroni over the offsets, "
                        "the noise criterion fails at 0.001; where the image is not biased)"}
#: A hand-in with this many times fewer samples than it declares: the noise criterion's power is reported for it.
FEWER = 4


def summarise(rows: list[dict], max_ratio: float | None = None) -> dict:
    """False alarms overall, per resolution group, renderer and file; raw detector p-values at or below 0.01; the
    noise variance ratios against mcrt at the declared spp, beside the rubric's ``max_ratio``."""
    def rate(sel):
        n = len(sel)
        fa = sum(1 for r in sel if r["lost"])
        return {"renders": n, "false_alarms": fa, "rate": fa / n if n else None}

    out = {"overall": rate(rows)}
    for key in ("group", "renderer", "file", "spp"):
        out[f"by_{key}"] = {str(v): rate([r for r in rows if r[key] == v]) for v in sorted({r[key] for r in rows}, key=str)}
    det = {}
    for name in DETECTORS:
        ps = []
        for r in rows:
            v = r.get(f"p_{name}")
            ps += [] if v is None else list(v) if isinstance(v, list) else [v]
        det[name] = {"tests": len(ps), "at_or_below_0.01": sum(p <= 0.01 for p in ps),
                     "at_or_below_0.05": sum(p <= 0.05 for p in ps), "at_or_below_0.001": sum(p <= 0.001 for p in ps)}
    out["detectors_raw"] = det
    out["noise_ratio"] = noise_ratios(rows, max_ratio)
    out["noise_shape"] = noise_shapes(rows)
    out["object_bias"] = object_bias(rows)
    out["criteria_lost"] = {}
    for r in rows:
        for n in r["lost"]:
            out["criteria_lost"][n] = out["criteria_lost"].get(n, 0) + 1
    return out


#: Renders at this many spp or more show an object's systematic difference from the reference above their noise.
BIAS_SPP = 256


def object_bias(rows: list[dict]) -> dict:
    """Each renderer's mean relative luminance difference from the reference per object, over its float renders at
    :data:`BIAS_SPP` spp or more (mean and its standard error over the renders): what a correct estimator differs
    by, which the per-object test must tolerate (min_effect) while a zero-difference test would not."""
    out = {}
    for name in sorted({r["renderer"] for r in rows}):
        sel = [r["objects_rel"] for r in rows if r["renderer"] == name and r["file"] == "float"
               and r["spp"] >= BIAS_SPP and r.get("objects_rel")]
        if len(sel) < 2:
            continue
        per = {}
        for obj in sel[0]:
            v = np.array([x[obj] for x in sel if obj in x])
            per[obj] = {"mean": float(v.mean()), "se": float(v.std(ddof=1) / np.sqrt(v.size)), "renders": int(v.size)}
        out[name] = per
    return out


def noise_ratios(rows: list[dict], max_ratio: float | None) -> dict:
    """The variance ratio (hand-in over mcrt at the declared spp) of the correct renders: quantiles, per renderer,
    the rubric's threshold and its margin over the largest ratio, and the share of each renderer's renders that
    a hand-in with :data:`FEWER` times fewer samples than declared would fail (its ratio times FEWER)."""
    v = np.array([r["var_ratio"] for r in rows if r.get("var_ratio") is not None], np.float64)
    if not v.size:
        return {}
    out = {"renders": int(v.size), "quantiles": {str(q): float(np.quantile(v, q)) for q in (0.5, 0.9, 0.99)},
           "max": float(v.max()), "max_ratio": max_ratio, "fewer": FEWER,
           "margin": None if max_ratio is None else float(max_ratio / v.max()),
           "above_threshold": None if max_ratio is None else int(np.sum(v > max_ratio)), "by_renderer": {}}
    for name in sorted({r["renderer"] for r in rows}):
        w = np.array([r["var_ratio"] for r in rows if r["renderer"] == name and r.get("var_ratio") is not None])
        if w.size:
            out["by_renderer"][name] = {"renders": int(w.size), "min": float(w.min()), "median": float(np.median(w)),
                                        "max": float(w.max()), "fewer_detected": None if max_ratio is None else
                                        float(np.mean(FEWER * w > max_ratio))}
    return out


def noise_shapes(rows: list[dict]) -> dict:
    """Per renderer, the range of the noise's shape statistic (:func:`mcrt.grade.stages.noise.unsampled_shape`) and
    how many renders were judged as a tracer's without light sampling, beside the bound: the estimators with light
    sampling must fall below it at any spp (a hand-in with fewer samples than declared keeps its estimator's shape),
    those without above it."""
    from mcrt.grade.stages.noise import UNSAMPLED_BODY, UNSAMPLED_SHAPE

    out = {"bound": UNSAMPLED_SHAPE, "body_bound": UNSAMPLED_BODY, "by_renderer": {}}
    for name in sorted({r["renderer"] for r in rows}):
        mine = [r for r in rows if r["renderer"] == name]
        w = np.array([r["unsampled_shape"] for r in mine if r.get("unsampled_shape") is not None])
        body = [r["unsampled_body"] for r in mine if r.get("unsampled_body") is not None]
        if w.size:
            out["by_renderer"][name] = {"renders": int(w.size), "min": float(w.min()), "max": float(w.max()),
                                        "min_body": min(body) if body else None,
                                        "judged_unsampled": sum(1 for r in mine if r.get("unsampled"))}
    return out


def markdown(data: dict) -> str:
    s = data["summary"]
    o = s["overall"]
    lines = ["# Grading: false alarms on correct renders", "",
             f"Generated by `{data['command']}` ({data['wall_time_s'] / 60:.0f} min). A false alarm is a correct render "
             "that loses points on any criterion but `resolution`; the rubric is course2023.toml's (64x64) and "
             "course2023_800.toml's (graded at 100x100), each test at the family-wise level 0.01 over tiles, objects, "
             "misregistration, blur, correlated noise and pixels (mcrt/grade/structure.py).", "",
             f"**Overall: {o['false_alarms']} false alarms in {o['renders']} correct renders.**", ""]
    for key, title in (("by_group", "hand-in -> graded resolution"), ("by_renderer", "renderer/sampler"),
                       ("by_spp", "spp"), ("by_file", "file")):
        lines += [f"| {title} | renders | false alarms |", "|---|---:|---:|"]
        lines += [f"| {k} | {v['renders']} | {v['false_alarms']} |" for k, v in s[key].items()]
        lines.append("")
    lines += ["Raw p-values of the structured-error detectors and the per-object tests (before the joint correction): "
              "the share at or below 0.01 should be about 0.01 for a calibrated test. The per-object test scores a "
              "difference beyond min_effect (mcrt/grade/objects.py); its test of a zero difference is shown beside "
              "it: what a correct renderer differs by on a whole object (next section) is resolved by it at high spp.", "",
              "| detector | tests | p <= 0.001 | p <= 0.01 | p <= 0.05 |", "|---|---:|---:|---:|---:|"]
    lines += [f"| {DETECTORS.get(k, k)} | {v['tests']} | {v.get('at_or_below_0.001', '')} | {v['at_or_below_0.01']} | "
              f"{v['at_or_below_0.05']} |" for k, v in s["detectors_raw"].items()]
    lines.append("")
    lines += _bias_markdown(s.get("object_bias") or {}, data.get("min_effect"))
    lines += _noise_markdown(s.get("noise_ratio") or {})
    lines += _shape_markdown(s.get("noise_shape") or {})
    fa = [r for r in data["cases"] if r["lost"]]
    if fa:
        lines += ["False alarms (the test that fired: the tile test, or a structured-error detector):", ""]
        lines += [f"- {r['renderer']} {r['spp']} spp {r['res']} px {r['file']} seed {r['seed']}: lost {', '.join(r['lost'])} "
                  f"({', '.join(k for k, v in (r['penalised'] or {}).items() if v) or 'tile test'})" for r in fa]
    return "\n".join(lines) + "\n"


def _bias_markdown(b: dict, min_effect: float | None) -> list[str]:
    if not b:
        return []
    objs = list(next(iter(b.values())))
    lines = ["## What correct renderers differ by, per object", "",
             f"Mean relative luminance difference from the reference (%) of each object over each renderer's float "
             f"renders at {BIAS_SPP} spp or more, with its standard error over the renders; a systematic difference "
             "is several standard errors from 0 for one renderer and not the others. The per-object and tile tests "
             "take points only for a difference significantly beyond min_effect"
             + (f" ({100 * min_effect:.1f} %)" if min_effect else "") + ".", "",
             "| renderer | renders | " + " | ".join(objs) + " |", "|---|---:|" + "---:|" * len(objs)]
    for name, per in b.items():
        n = max(v["renders"] for v in per.values())
        lines.append(f"| {name} | {n} | " + " | ".join(
            f"{100 * per[o]['mean']:+.2f} ± {100 * per[o]['se']:.2f}" if o in per else "" for o in objs) + " |")
    return lines + [""]


def _noise_markdown(n: dict) -> list[str]:
    if not n:
        return []
    q = n["quantiles"]
    lines = ["## Noise against the declared spp", "",
             "The noise criterion's variance ratio of each correct render: its noise variance over mcrt's at the "
             "declared spp (mcrt.grade.stages.noise; 1 is mcrt's own, below 1 a more efficient estimator). "
             f"Over {n['renders']} correct renders: median {q['0.5']:.2f}, 90 % {q['0.9']:.2f}, 99 % {q['0.99']:.2f}, "
             f"largest **{n['max']:.2f}**."]
    if n.get("max_ratio") is not None:
        lines[-1] += (f" The rubric fails a ratio above noise.max_ratio = **{n['max_ratio']:g}**: "
                      f"{n['margin']:.2f} times the largest correct ratio; {n['above_threshold']} correct renders "
                      f"above it. *{n['fewer']}x fewer*: the share of each renderer's renders whose ratio times "
                      f"{n['fewer']} exceeds it, i.e. a hand-in rendered with {n['fewer']} times fewer samples than "
                      "it declares that the criterion fails.")
    lines += ["", f"| renderer | renders | min | median | max | {n['fewer']}x fewer detected |", "|---|---:|---:|---:|---:|---:|"]
    for k, v in n["by_renderer"].items():
        det = "" if v["fewer_detected"] is None else f"{100 * v['fewer_detected']:.0f} %"
        lines.append(f"| {k} | {v['renders']} | {v['min']:.2f} | {v['median']:.2f} | {v['max']:.2f} | {det} |")
    return lines + [""]


def _shape_markdown(n: dict) -> list[str]:
    if not n.get("by_renderer"):
        return []
    lines = ["## The shape of the noise: a tracer without light sampling", "",
             "A hand-in noisier than noise.max_ratio allows is judged as a tracer's without light sampling (the light "
             "found only by bouncing into it: correct, and far noisier where the light is direct) when its noise follows "
             "that tracer's shape more closely than mcrt's by more than the bound "
             f"(mcrt.grade.stages.noise.unsampled_shape: **{n['bound']:g}**) and the body of its noise against that "
             f"tracer's model is at least **{n.get('body_bound', 0):g}** (a bias the shape alone would take for it "
             "gives less); its ratio is then taken against that tracer. The shape does not depend on the noise's "
             "level, so a hand-in with fewer samples than it declares keeps its estimator's: the estimators with light "
             "sampling must stay below the bound, those without above it. *Smallest body*: over the renders whose "
             "shape passed.", "",
             "| renderer | renders | smallest shape | largest shape | smallest body | judged without light sampling |",
             "|---|---:|---:|---:|---:|---:|"]
    for k, v in n["by_renderer"].items():
        body = "" if v.get("min_body") is None else f"{v['min_body']:.2f}"
        lines.append(f"| {k} | {v['renders']} | {v['min']:.2f} | {v['max']:.2f} | {body} | {v['judged_unsampled']} |")
    return lines + [""]


def register(sub) -> None:
    p = sub.add_parser("grade-false-alarms", help="how often grading takes points from correct renders (a report)",
                       description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--out", default="reports/grading/false_alarms", help="report folder (default: reports/grading/false_alarms)")
    p.add_argument("--seeds", type=int, default=3, help="renders per setting at 64x64, one fewer at larger sizes (default: 3)")
    p.add_argument("--cache", default=None, help="folder of the cached expected images (default: $MCRT_CACHE/grade or "
                   "~/.cache/mcrt/grade)")
    p.add_argument("--quiet", "-q", action="store_true", help="no progress lines (default: off)")
    p.set_defaults(func=_run)


def _run(args) -> int:
    data = run_study(Path(args.out), seeds=args.seeds, cache=args.cache, progress=not args.quiet)
    o = data["summary"]["overall"]
    print(f"{o['false_alarms']} false alarms in {o['renders']} correct renders; report in {args.out}/index.md")
    return EXIT_OK if o["false_alarms"] == 0 else EXIT_FAILED
