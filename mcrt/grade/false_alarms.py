"""How often the grader takes points from a correct render: ``mcrt grade-false-alarms``.

Correct renders of the course scene from several estimators and samplers
(mcrt; Mitsuba's ``path`` with its ``independent``, ``stratified``,
``ldsampler`` and ``multijitter`` samplers, ``volpath``), at 16 to 1024
spp, at hand-in resolutions from 64x64 (graded at 64x64) to 800x800 (graded
at 100x100), as float images and as 8-bit PNGs in the common encodings, are
graded with the course's rubric. A *false alarm* is any point lost on a
criterion that judges the rendering (everything but ``resolution``, which a
hand-in at another resolution loses by design). The report gives the rate
overall and per group, and the raw p-values of each structured-error
detector (:mod:`mcrt.grade.structure`), whose share of those at or below
0.01 should be near 0.01 (or below, for the conservative pixel bound).

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
    renderer: str  # "mcrt", or "path/<sampler>", "volpath/<sampler>" (Mitsuba)
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
    return out


def render_case(scene, c: Case) -> np.ndarray:
    """The case's image, (res, res, 3) float64 linear radiance."""
    if c.renderer == "mcrt":
        from mcrt.render import render

        s = scene.settings(camera="near", width=c.res, height=c.res, spp=c.spp, max_depth=8)
        return render(scene, s, seed=c.seed, progress=False).mean.astype(np.float64)
    from mcrt.mitsuba_scene import render_with_variance, scene_dict

    integrator, sampler = c.renderer.split("/")
    d = scene_dict(scene, "near", c.res, c.res, 8, integrator=integrator)
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
            rows.append({**c.__dict__, "group": c.group, "score": r.score, "max_score": r.max_score,
                         "lost": _false_alarm(r), "p_registration": reg.get("p"), "p_blur": st.get("p_blur"),
                         "p_correlation": st.get("p_correlation"), "penalised": st.get("penalised"),
                         "encoding": (r.details.get("encoding") or {}).get("detected")})
            bar.update(k + 1)
    summary = summarise(rows)
    data = {"command": f"mcrt {COMMAND}" + (f" --seeds {seeds}" if seeds != 3 else ""), "seeds": seeds,
            "wall_time_s": time.perf_counter() - t0, "summary": summary, "cases": rows}
    out.mkdir(parents=True, exist_ok=True)
    (out / "false_alarms.json").write_text(json.dumps(data, indent=1) + "\n")
    (out / "index.md").write_text(markdown(data))
    return data


def summarise(rows: list[dict]) -> dict:
    """False alarms overall, per resolution group, renderer and file; raw detector p-values at or below 0.01."""
    def rate(sel):
        n = len(sel)
        fa = sum(1 for r in sel if r["lost"])
        return {"renders": n, "false_alarms": fa, "rate": fa / n if n else None}

    out = {"overall": rate(rows)}
    for key in ("group", "renderer", "file", "spp"):
        out[f"by_{key}"] = {str(v): rate([r for r in rows if r[key] == v]) for v in sorted({r[key] for r in rows}, key=str)}
    det = {}
    for name in ("p_registration", "p_blur", "p_correlation"):
        ps = [r[name] for r in rows if r[name] is not None]
        det[name[2:]] = {"tests": len(ps), "at_or_below_0.01": sum(p <= 0.01 for p in ps),
                         "at_or_below_0.05": sum(p <= 0.05 for p in ps)}
    out["detectors_raw"] = det
    out["criteria_lost"] = {}
    for r in rows:
        for n in r["lost"]:
            out["criteria_lost"][n] = out["criteria_lost"].get(n, 0) + 1
    return out


def markdown(data: dict) -> str:
    s = data["summary"]
    o = s["overall"]
    lines = ["# Grading: false alarms on correct renders", "",
             f"Generated by `{data['command']}` ({data['wall_time_s'] / 60:.0f} min). A false alarm is a correct render "
             "that loses points on any criterion but `resolution`; the rubric is course2023.toml's (64x64) and "
             "course2023_800.toml's (graded at 100x100), each test at the family-wise level 0.01 over tiles, "
             "misregistration, blur, correlated noise and pixels (mcrt/grade/structure.py).", "",
             f"**Overall: {o['false_alarms']} false alarms in {o['renders']} correct renders.**", ""]
    for key, title in (("by_group", "hand-in -> graded resolution"), ("by_renderer", "renderer/sampler"),
                       ("by_spp", "spp"), ("by_file", "file")):
        lines += [f"| {title} | renders | false alarms |", "|---|---:|---:|"]
        lines += [f"| {k} | {v['renders']} | {v['false_alarms']} |" for k, v in s[key].items()]
        lines.append("")
    lines += ["Raw p-values of the structured-error detectors (before the joint correction): the share at or below "
              "0.01 should be about 0.01 for a calibrated test.", "",
              "| detector | tests | p <= 0.01 | p <= 0.05 |", "|---|---:|---:|---:|"]
    lines += [f"| {k} | {v['tests']} | {v['at_or_below_0.01']} | {v['at_or_below_0.05']} |" for k, v in s["detectors_raw"].items()]
    lines.append("")
    fa = [r for r in data["cases"] if r["lost"]]
    if fa:
        lines += ["False alarms (the test that fired: the tile test, or a structured-error detector):", ""]
        lines += [f"- {r['renderer']} {r['spp']} spp {r['res']} px {r['file']} seed {r['seed']}: lost {', '.join(r['lost'])} "
                  f"({', '.join(k for k, v in (r['penalised'] or {}).items() if v) or 'tile test'})" for r in fa]
    return "\n".join(lines) + "\n"


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
