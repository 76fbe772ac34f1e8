"""What grading writes: results.json (Gradescope), feedback.html, grades.csv, the class summary.

Per student, under ``DIR/<student>/``:

* ``results.json``: Gradescope's autograder format (``score``, ``max_score``,
  ``execution_time``, ``output``, ``tests[]`` with ``name``, ``score``,
  ``max_score``, ``output``, ``visibility``, ``status``), and everything
  the grader measured under ``extra_data`` (schema :data:`SCHEMA`).
  Written for every student, also when grading crashed or timed out.
* ``feedback.html``: one self-contained page (images embedded as base64
  PNGs): the tests, the student's image beside the reference, the heat map
  of the relative difference per tile (blue too dark, red too bright,
  penalised tiles outlined), the significance map, the pattern of the bug
  the image most resembles, the FLIP error map, notes.

For the class, under ``DIR/``: ``grades.csv`` (one row per student, one
column per criterion) and ``summary.md`` / ``summary.json`` (score
distribution, points lost per criterion, most common diagnoses, students
not graded).
"""

from __future__ import annotations

import base64
import csv
import html
import io
import json
import math
import re
import statistics
from collections import Counter
from pathlib import Path

import numpy as np
from PIL import Image

from mcrt.stats.tiles import tile_box, tile_expand
from mcrt.util import atomic
from mcrt.util.fmt import short as _num
from mcrt.util.jsonsafe import json_safe

SCHEMA = "mcrt.grade.results/1"
DIFF_VMAX = 0.25  # the relative-difference maps saturate at +-25 %
FIG_MIN = 256  # figures are enlarged (nearest neighbour) to at least this many pixels across


# --------------------------------------------------------------------------
# Figures
# --------------------------------------------------------------------------


def diverging(x: np.ndarray, vmax: float = DIFF_VMAX) -> np.ndarray:
    """Signed values to RGB uint8: white at 0, blue for negative (too dark), red for positive (too bright)."""
    s = np.clip(np.nan_to_num(np.asarray(x, np.float64)) / vmax, -1.0, 1.0)
    pos, neg = np.maximum(s, 0), np.maximum(-s, 0)
    rgb = np.stack([1 - 0.8 * neg, 1 - 0.8 * (pos + neg), 1 - 0.8 * pos], axis=-1)
    return np.round(255 * rgb).astype(np.uint8)


def diff_scale(rel: np.ndarray) -> float:
    """Colour-scale limit for relative differences: the smallest of 5, 10, 25, 50, 100, 200 % above
    the 95th percentile of |rel| (so most tiles are not saturated)."""
    a = np.abs(np.nan_to_num(np.asarray(rel, np.float64)))
    q = float(np.percentile(a, 95)) if a.size else 0.0
    for v in (0.05, 0.10, 0.25, 0.5, 1.0, 2.0):
        if q <= v:
            return v
    return 5.0


def _scale(shape) -> int:
    return max(1, math.ceil(FIG_MIN / max(shape[1], 1)))


def _enlarge(img: np.ndarray, s: int) -> np.ndarray:
    return np.repeat(np.repeat(img, s, axis=0), s, axis=1)


def tile_figure(tiles: np.ndarray, shape, tile: int, flagged: np.ndarray | None = None, vmax: float = DIFF_VMAX) -> np.ndarray:
    """A per-tile signed map enlarged for viewing, with flagged tiles outlined in black."""
    s = _scale(shape)
    h, w = shape
    img = _enlarge(diverging(tile_expand(tiles, h, w, tile), vmax), s)
    if flagged is not None:
        for ty, tx in zip(*np.nonzero(flagged)):
            y0, y1, x0, x1 = (s * b for b in tile_box(h, w, tile, int(ty), int(tx)))
            img[y0:y1, x0:x0 + 1] = img[y0:y1, x1 - 1:x1] = 0
            img[y0:y0 + 1, x0:x1] = img[y1 - 1:y1, x0:x1] = 0
    return img


def png_base64(img: np.ndarray) -> str:
    buf = io.BytesIO()
    Image.fromarray(np.ascontiguousarray(img), "RGB").save(buf, format="PNG")
    return base64.b64encode(buf.getvalue()).decode("ascii")


def render_figures(fig: dict) -> list[tuple[str, str, str]]:
    """(title, caption, base64 PNG) for the feedback page."""
    from mcrt.image_files import tonemap

    out = []
    if "submission" not in fig:
        return out
    shape = fig["submission"].shape[:2]
    s = _scale(shape)
    out.append(("Your image", "as graded (after any correction listed above), sRGB preview", png_base64(_enlarge(tonemap(fig["submission"]), s))))
    out.append(("Reference", "the expected image, same preview", png_base64(_enlarge(tonemap(fig["reference"]), s))))
    tile = fig["tile"]
    vmax = diff_scale(fig["rel_tiles"])
    out.append(("Relative difference per tile", (f"blue: too dark, red: too bright, saturating at +-{100 * vmax:g} %; "
                "outlined: penalised tiles"), png_base64(tile_figure(fig["rel_tiles"], shape, tile, fig["penalised"], vmax=vmax))))
    out.append(("Significance per tile", "the tile statistic t (noise-normalised difference), saturating at |t| = 5",
                png_base64(tile_figure(np.clip(fig["t_tiles"] / 5.0, -1, 1), shape, tile, fig["penalised"], vmax=1.0))))
    if "mutant_rel_tiles" in fig:
        out.append((f"Pattern of the closest bug ({fig['mutant_name']})", ("what this bug would do to a correct image, same "
                    "colours as the relative difference"), png_base64(tile_figure(fig["mutant_rel_tiles"], shape, tile, vmax=vmax))))
    if "objects_rel" in fig:
        out.append(("Where something else is wrong, by object", ("each surface the rest of the difference sits on (after "
                    "the closest explanation), same colours as the relative difference"),
                    png_base64(_enlarge(diverging(fig["objects_rel"], vmax), s))))
    if "flip" in fig and fig["flip"] is not None:
        f = np.asarray(fig["flip"])
        if f.ndim == 3 and f.shape[2] == 3:
            f8 = f if f.dtype == np.uint8 else np.round(np.clip(f, 0, 1) * 255).astype(np.uint8)
            out.append(("FLIP error map", "perceived difference (NVIDIA FLIP, HDR); noise shows too", png_base64(_enlarge(f8, s))))
    return out


# --------------------------------------------------------------------------
# Per student
# --------------------------------------------------------------------------


#: What a student can do about a failed criterion (results.json, per test); ``{...}`` from the assignment.
ADVICE = {
    "readable": "Save your render in one of the accepted formats and check that it opens in an image viewer before you upload it.",
    "resolution": "Render at exactly {width}x{height} pixels.",
    "finite": "Look for divisions by a zero pdf or length and for normalised zero vectors; a NaN pixel usually has one bad path.",
    "non_negative": "Radiance is never negative: look for a sign error (a cosine or a normal pointing the wrong way).",
    "linear": "Write linear radiance to EXR/PFM/HDR (no gamma); a PNG gets the sRGB curve once (or declare `linear = true`).",
    "orientation": "Row 0 of the file is the top of the image and column 0 its left; check your loops and camera vectors.",
    "camera": "Render with the '{camera}' camera of the scene.",
    "exposure": "Do not scale the image; check the light's radiance and that you divide by the number of samples.",
    "noise": "Render with at least {min_spp} samples per pixel and declare them (`spp = N` in manifest.toml); if you did, "
             "your estimator has more variance than it should.",
    "unbiased": "Start with the closest bug named below, in the part of the image the map shows.",
    "unbiased/undiagnosed": "Look at the part of the image the map shows and at the estimator terms that light it.",
}

_MD_SPECIAL = str.maketrans({c: "\\" + c for c in "\\`*_[]<>#|~!&"})


def md_text(text: str) -> str:
    """``text`` as Markdown, whatever it holds: one line escaped; several lines (a traceback, a table) in a fenced
    block whose fence is longer than any run of backticks in the text, so that no line of it can close the block
    (a tilde line cannot close a backtick fence at all; CommonMark, "Fenced code blocks")."""
    text = str(text).replace("\r\n", "\n").replace("\r", "\n")
    if "\n" in text.strip():
        fence = "`" * max(3, 1 + max(map(len, re.findall(r"`+", text)), default=0))
        return f"{fence}text\n{text.strip()}\n{fence}"
    return text.translate(_MD_SPECIAL)


def difference_map(fig: dict, limit: int = 24) -> str | None:
    """Where the image differs, as text: the relative difference of each base tile in per cent (luminance),
    penalised tiles marked ``*``, top row first; None without figures or for grids above ``limit`` tiles."""
    rel, pen = fig.get("rel_tiles"), fig.get("penalised")
    if rel is None or np.ndim(rel) != 2 or max(np.shape(rel)) > limit:
        return None
    rel = np.clip(np.nan_to_num(np.asarray(rel, np.float64)) * 100, -999, 999)
    pen = np.zeros(rel.shape, bool) if pen is None else np.asarray(pen, bool)
    rows = [" ".join(f"{int(round(v)):+4d}{'*' if p else ' '}" for v, p in zip(r, pr)) for r, pr in zip(rel, pen)]
    tile = fig.get("tile", 0)
    head = (f"Relative difference from the reference per {tile}x{tile}-pixel tile, in % (minus: too dark, plus: too "
            "bright; \\* penalised), top row first:")
    return head + "\n\n```text\n" + "\n".join(rows) + "\n```"


def _advice(name: str, assignment) -> str:
    """ADVICE[name] (Markdown, written here) with the assignment's numbers."""
    text = ADVICE.get(name, "")
    try:
        return text.format(width=assignment.width, height=assignment.height, camera=assignment.camera, min_spp=assignment.min_spp)
    except (AttributeError, KeyError, IndexError, ValueError):
        return text


def _diagnosis_md(res) -> list[str]:
    lines = []
    for i, d in enumerate(res.diagnosis[:2], 1):
        expl = (f" (explains {100 * d['explained']:.0f} % of the difference)"
                if isinstance(d.get("explained"), (int, float)) and d["explained"] > 0 else "")
        where = f" This bug would make the image {d['where']}." if d.get("where") else ""
        lines.append(f"{i}. **{md_text(d['mutant'])}**: {md_text(str(d.get('description', '')).rstrip('.') + expl + '.' + where)}")
    return lines


def test_output_md(t, res, assignment) -> str:
    """One test's output for results.json (Markdown): the check's message, what to do when it failed, and for
    the bias test the closest catalogued bugs and the map of where the image differs."""
    parts = [md_text(t.output)]
    key = "unbiased/undiagnosed" if t.name == "unbiased" and not res.diagnosis else t.name
    if t.status == "failed" and t.max_score > 0 and _advice(key, assignment):
        parts.append(f"**What to do:** {_advice(key, assignment)}")
    if t.name in ("unbiased", "noise") and t.status == "failed":
        if res.diagnosis and (t.name == "unbiased" or not any(x.name == "unbiased" and x.status == "failed" for x in res.tests)):
            parts.append("**Closest bugs of the catalogue:**\n\n" + "\n".join(_diagnosis_md(res)))
        m = difference_map(res.figures) if t.name == "unbiased" else None
        if m:
            parts.append(m)
    return "\n\n".join(parts)


def results_json(res, assignment) -> dict:
    """Gradescope's results.json for one student.

    Everything a student needs is in the file itself, since Gradescope shows
    them nothing else: the top-level ``output`` and each test's ``output`` are
    Markdown (``output_format`` and ``test_output_format`` "md"), with the
    diagnosis, the map of where the image differs and what to do.
    """
    tests = []
    for t in res.tests:
        tests.append({
            "name": t.title, "score": t.score, "max_score": t.max_score, "output": test_output_md(t, res, assignment),
            "output_format": "md", "visibility": t.visibility,
            "status": "passed" if t.status in ("passed", "info") else "failed", "tags": [t.name],
        })
    lines = [md_text(res.summary)]
    if res.diagnosis:
        lines += ["", "**Closest bugs of the catalogue:**", "", *_diagnosis_md(res)]
    m = difference_map(res.figures)
    if m and any(t.name == "unbiased" and t.status == "failed" for t in res.tests):
        lines += ["", m]
    if res.notes:
        lines.append("")
        lines += [f"- Note: {md_text(n)}" if "\n" not in n.strip() else f"Note:\n\n{md_text(n)}" for n in res.notes]
    return json_safe({
        "score": res.score,
        "max_score": res.max_score,
        "execution_time": round(res.elapsed, 3),
        "output": "\n".join(lines),
        "output_format": "md",
        "test_output_format": "md",
        "visibility": "visible",
        "stdout_visibility": "hidden",
        "tests": tests,
        "extra_data": {
            "schema": SCHEMA, "student": res.student, "status": res.status, "assignment": assignment.name,
            "diagnosis": res.diagnosis, "notes": res.notes, "details": res.details,
        },
    })


def write_json_atomic(path: Path, data: dict) -> None:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    atomic.write_text(path, json.dumps(data, indent=1, allow_nan=False), fsync=False)


def write_student(res, assignment, out_dir: Path) -> Path:
    """Write DIR/<student>/results.json and feedback.html; returns the student's folder."""
    d = Path(out_dir) / res.student
    d.mkdir(parents=True, exist_ok=True)
    write_json_atomic(d / "results.json", results_json(res, assignment))
    try:
        atomic.write_text(d / "feedback.html", feedback_html(res, assignment), errors="replace", fsync=False)
    except Exception as e:  # noqa: BLE001 - the page is a courtesy; results.json is what counts
        (d / "feedback.html").write_text(f"<p>feedback page could not be written: {html.escape(str(e))}</p>",
                                         encoding="utf-8", errors="replace")
    return d


_CSS = """
body{font-family:system-ui,sans-serif;max-width:1100px;margin:2em auto;padding:0 1em;color:#222}
table{border-collapse:collapse;width:100%}td,th{border-bottom:1px solid #ddd;padding:.4em;text-align:left;vertical-align:top}
.passed{color:#1a7f37}.failed{color:#cf222e}.info{color:#555}.notgraded{color:#9a6700}
.figs{display:flex;flex-wrap:wrap;gap:1em}.fig{width:280px}.fig img{image-rendering:pixelated;width:256px;border:1px solid #ccc}
.small{font-size:.85em;color:#555}code{background:#f4f4f4;padding:0 .2em}pre{white-space:pre-wrap;font-size:.85em;margin:0}
"""




def feedback_html(res, assignment) -> str:
    e = html.escape
    rows = []
    for t in res.tests:
        cls = t.status.replace(" ", "")
        body = f"<pre>{e(t.output)}</pre>" if "\n" in t.output else e(t.output)
        rows.append(f"<tr><td>{e(t.title)}</td><td class='{cls}'>{e(t.status)}</td>"
                    f"<td>{_num(t.score)} / {_num(t.max_score)}</td><td>{body}</td></tr>")
    diag = ""
    if res.diagnosis:
        items = []
        for d in res.diagnosis[:2]:
            expl = f" (explains {100 * d['explained']:.0f} % of the difference)" if d.get("explained") is not None and d["explained"] > 0 else ""
            amp = ""
            if d.get("amplitude") is not None and d["amplitude"] > 0 and abs(d["amplitude"] - 1) > 0.35:
                amp = f"; your image shows the same pattern at about {d['amplitude']:.1f} times its strength, a variant of this bug"
            where = f"<br><span class='small'>This bug would make the image {e(d['where'])}.</span>" if d.get("where") else ""
            items.append(f"<li><b>{e(d['mutant'])}</b>: {e(d['description'])}{e(expl)}{e(amp)}{where}</li>")
        diag = "<h2>What it most resembles</h2><ol>" + "".join(items) + "</ol>"
    figs = ""
    try:
        f = render_figures(res.figures)
    except Exception:  # noqa: BLE001 - a page without figures beats no page
        f = []
    if f:
        figs = "<h2>Images</h2><div class='figs'>" + "".join(
            f"<div class='fig'><b>{e(t)}</b><br><img alt='{e(t)}' src='data:image/png;base64,{b}'><br>"
            f"<span class='small'>{e(c)}</span></div>" for t, c, b in f) + "</div>"
    notes = ""
    if res.notes:
        notes = "<h2>Notes</h2><ul>" + "".join(f"<li>{e(n)}</li>" for n in res.notes) + "</ul>"
    if res.details.get("mode") == "code":
        how = ("<h2>How this was graded</h2><p class='small'>Each function ran in a separate process with a time and "
               "memory limit, in a sandbox (only its own folder writable; no processes, network or signals), on inputs "
               "fixed by the grader, and its results went through statistical checks (chi-square goodness of fit, closed "
               "forms, comparison with the reference image).</p>")
    else:
        how = f"""<h2>How this was graded</h2>
<p class="small">Your image is compared with a high-sample reference tile by tile, at several tile sizes, with a
statistical test that knows how noisy a correct image at your sample count is (measured from your own image, from
your second render if you handed one in, and from the reference renderer at your sample count). A difference counts
only if it is significant after correcting for the number of tests (Holm, family-wise error rate
{assignment.thresholds.alpha:g}) and larger than {100 * assignment.thresholds.min_effect:.2g} % of the brightness:
an honest noisy image is not penalised. {e(res.details.get("reference_source", ""))}</p>"""
    m = res.details.get("metrics", {})
    met = ""
    if m:
        met = ("<p class='small'>" + e(", ".join(f"{k} {v:.4g}" for k, v in m.items() if isinstance(v, (int, float)))) + "</p>")
    return f"""<!DOCTYPE html><html><head><meta charset="utf-8"><title>Feedback: {e(res.student)}</title>
<style>{_CSS}</style></head><body>
<h1>{e(assignment.title)}: {e(res.student)}</h1>
<p><b>Score: {_num(res.score)} / {_num(res.max_score)}</b>. {e(res.summary.split(". ", 1)[1] if ". " in res.summary else "")}</p>
<table><tr><th>Check</th><th>Result</th><th>Points</th><th>Details</th></tr>{''.join(rows)}</table>
{diag}{figs}{notes}{how}
{met}</body></html>"""


# --------------------------------------------------------------------------
# The class
# --------------------------------------------------------------------------


def write_class(results: list, assignment, out_dir: Path, *, elapsed: float = 0.0, context_note: str = "",
                criteria: list[tuple[str, float, str]] | None = None, power: list[dict] | None = None,
                pending: list[str] | None = None) -> dict:
    """Write grades.csv, summary.md and summary.json (each by an atomic rename); return the summary dict.

    ``criteria`` (name, points, title) defaults to the image rubric (code mode passes its checks); ``pending``
    names the students of an unfinished run not graded yet: the summary then says the run is incomplete.
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    criteria = criteria if criteria is not None else [(c.name, c.points, c.title) for c in assignment.rubric]
    _write_grades_csv(out / "grades.csv", results, [c[0] for c in criteria])
    summ = _class_summary(results, assignment, criteria, elapsed=elapsed, context_note=context_note, power=power,
                          pending=pending)
    write_json_atomic(out / "summary.json", summ)
    lines = _summary_md(summ, assignment, [r.score for r in results])
    atomic.write_text(out / "summary.md", "\n".join(lines), fsync=False)
    return summ


def _write_grades_csv(path: Path, results: list, crit: list[str]) -> None:
    """grades.csv: one row per student (sorted by id), one column per criterion named in ``crit``."""
    with (atomic.replacing(path, fsync=False) as tmp,
          open(tmp, "w", newline="", encoding="utf-8", errors="replace") as f):
        w = csv.writer(f)
        w.writerow(["student", "status", "score", "max_score", *crit, "diagnosis", "summary", "seconds"])
        for r in sorted(results, key=lambda r: r.student):
            by = {t.name: t.score for t in r.tests}
            top = r.diagnosis[0]["mutant"] if r.diagnosis else ""
            w.writerow([r.student, r.status, f"{r.score:g}", f"{r.max_score:g}", *(f"{by.get(c, 0):g}" for c in crit), top,
                        r.summary[:300], f"{r.elapsed:.2f}"])


def _class_summary(results: list, assignment, criteria: list[tuple[str, float, str]], *, elapsed: float,
                   context_note: str, power: list[dict] | None, pending: list[str] | None) -> dict:
    """summary.json's content: scores, points lost per criterion, diagnoses, whether the run is complete."""
    maxs = sum(c[1] for c in criteria)
    scores = [r.score for r in results]
    summ = {
        "schema": "mcrt.grade.summary/1", "assignment": assignment.name, "students": len(results),
        "graded": sum(r.status == "graded" for r in results),
        "not_graded": [{"student": r.student, "status": r.status, "reason": r.summary} for r in results if r.status != "graded"],
        "max_score": maxs,
        "mean": statistics.fmean(scores) if scores else None,
        "median": statistics.median(scores) if scores else None,
        "min": min(scores) if scores else None, "max": max(scores) if scores else None,
        "full_marks": sum(abs(s - maxs) < 1e-9 for s in scores),
        "criteria": {}, "diagnoses": {}, "seconds": elapsed, "context": context_note,
        "complete": not pending, "pending": list(pending or []),
    }
    for name, points, _ in criteria:
        lost = [r for r in results for t in r.tests if t.name == name and t.score < t.max_score - 1e-9]
        pts = [t.score for r in results for t in r.tests if t.name == name]
        summ["criteria"][name] = {"points": points, "students_losing_points": len(lost),
                                  "mean_score": statistics.fmean(pts) if pts else None}
    summ["diagnoses"] = dict(Counter(r.diagnosis[0]["mutant"] for r in results if r.diagnosis).most_common())
    if power:
        summ["catalogue_power"] = power
    return summ


def _summary_md(summ: dict, assignment, scores: list[float]) -> list[str]:
    """summary.md's lines: everything in :func:`_class_summary`'s dict, and the distribution of ``scores``."""
    maxs, pending = summ["max_score"], summ["pending"]
    lines = [f"# {assignment.title}: class summary", ""]
    if pending:
        lines += [f"**Incomplete:** {len(pending)} more student(s) to grade ({', '.join(md_text(p) for p in pending[:20])}"
                  f"{', ...' if len(pending) > 20 else ''}). The run was stopped or is still running (run.json); "
                  "`mcrt grade` with the same output folder grades only those.", ""]
    lines += [f"{summ['students']} students, {summ['graded']} graded; scores out of {maxs:g}."]
    if scores:
        lines.append(f"Mean {summ['mean']:.1f}, median {summ['median']:.1f}, min {summ['min']:g}, max {summ['max']:g}; "
                     f"{summ['full_marks']} with full marks.")
        lines += ["", "## Score distribution", "", "```"]
        bins = np.linspace(0, maxs if maxs > 0 else 1, 11)
        hist, _ = np.histogram(np.clip(scores, 0, maxs), bins=bins)
        for lo, hi, n in zip(bins[:-1], bins[1:], hist):
            lines.append(f"{lo:6.1f} - {hi:6.1f} | {'#' * int(n)} {n}")
        lines.append("```")
    lines += ["", "## Points lost per criterion", "", "| criterion | points | students losing points | mean score |",
              "|---|---|---|---|"]
    for name, c in summ["criteria"].items():
        ms = "" if c["mean_score"] is None else f"{c['mean_score']:.2f}"
        lines.append(f"| {name} | {c['points']:g} | {c['students_losing_points']} | {ms} |")
    if summ["diagnoses"]:
        lines += ["", "## Most common diagnoses (closest catalogued bug)", ""]
        lines += [f"- {m}: {n} student{'s' if n != 1 else ''}" for m, n in summ["diagnoses"].items()]
    if summ.get("catalogue_power"):
        lines += _power_md(summ["catalogue_power"], assignment)
    if summ["not_graded"]:
        lines += ["", "## Not graded (score 0, results.json written)", ""]
        lines += [f"- {md_text(d['student'])} ({d['status']}): {md_text(' '.join(str(d['reason']).split()))}"
                  for d in summ["not_graded"]]
    lines += ["", f"Grading took {summ['seconds']:.1f} s. {summ['context']}".rstrip(), ""]
    return lines


def _power_md(power: list[dict], assignment) -> list[str]:
    """The summary's table of which catalogued bugs the bias test sees at the assignment's spp."""
    lines = ["", f"## Which catalogued bugs the bias test sees at {assignment.spp} spp", "",
             ("Expected largest tile statistic |z| of a render with the bug, against Holm's first threshold "
              f"{power[0]['z_crit']:.2f}; 'spp needed' gives about 84 % power at the best tile."), "",
             "| bug | expected max z | seen at this spp | spp needed |", "|---|---|---|---|"]
    for p in sorted(power, key=lambda p: -p["z_max"]):
        need = f"({p.get('limit') or 'unknown'})" if p["spp_needed"] is None else f"{p['spp_needed']}"
        lines.append(f"| {p['mutant']} | {p['z_max']:.1f} | {'yes' if p['detectable'] else 'no'} | {need} |")
    return lines
