"""The hard-case report as Markdown: reports/hardcases/index.md."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

from mcrt.hardcases.cases import ALPHA, SEEDS, TILE, CaseResult
from mcrt.hardcases.convergence import CONVERGENCE_REF_SPP, CONVERGENCE_RES, ConvergenceRow, convergence_slope
from mcrt.hardcases.sweep import SweepRow, sweep_limits


def _fmt(x, spec=".3g", none="-") -> str:
    """A number for a table cell: ``none`` for None, NaN spelled out."""
    if x is None:
        return none
    if isinstance(x, float) and math.isnan(x):
        return "NaN"
    return format(x, spec)


def case_table(results: list[CaseResult]) -> list[str]:
    """The table of cases: health, agreement, errors and times of every render (also printed by the command)."""
    lines = [
        ("| case | camera | NaN/Inf (mcrt, Mitsuba) | negative (mcrt, Mitsuba) | mcrt vs Mitsuba (equal spp) | max abs t | "
         "rel. RMSE mcrt @N | rel. RMSE Mitsuba @N | Mitsuba spp @T | rel. RMSE Mitsuba @T | mcrt s | Mitsuba s | verdict |"),
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in results:
        a, b, e = r.renders.get("mcrt"), r.renders.get("mitsuba"), r.renders.get("mitsuba_equal_time")
        v = r.comparisons.get("mcrt_vs_mitsuba")
        agree = "-" if v is None else ("agree" if v.passed else f"DIFFER ({v.n_rejected} tiles)" if v.n_rejected is not None else "not comparable")
        u = r.comparisons.get("mcrt_vs_untransformed")
        if u is not None:
            agree += "; image unchanged" if u.passed else "; IMAGE CHANGED"
        if r.expect == "refused":
            verdict = "refused by the guard (expected)" if not r.guard["ok"] else "FAIL: accepted"
        elif r.passed:
            verdict = "pass"
        else:
            verdict = "FAIL (known issue)" if r.known_issue else "FAIL"
        lines.append(
            f"| {r.name} | {r.camera} | {a.nonfinite if a else '-'}, {b.nonfinite} | {a.negative if a else '-'}, {b.negative} | {agree} | "
            f"{_fmt(v.max_abs_t if v else None, '.2f')} | {_fmt(a.rel_rmse if a else None)} | {_fmt(b.rel_rmse)} | "
            f"{e.spp if e else '-'} | {_fmt(e.rel_rmse if e else None)} | {_fmt(a.render_time if a else None, '.2f')} | "
            f"{_fmt(b.render_time, '.2f')} | {verdict} |"
        )
    return lines


def _limit_text(lim: dict[str, Any]) -> str:
    def g(v):
        return "none tested" if v is None else f"{v:g}"

    if lim["kind"] == "moved":
        text = f"right up to an offset of {g(lim['right_up_to'])}, wrong from {g(lim['wrong_from'])}"
        if lim["renderer"] == "mcrt" and lim["guard_accepts_up_to"] is not None:
            text += f"; the guard accepts up to {g(lim['guard_accepts_up_to'])}"
        return text
    (lo, hi), (lo_bad, hi_bad) = lim["right_up_to"], lim["wrong_from"]
    if lo is None and hi is None:
        return f"wrong at every tested factor (nearest to 1: {g(lo_bad)} and {g(hi_bad)})"
    return f"right for scale factors from {g(lo)} to {g(hi)}, wrong at {g(lo_bad)} and {g(hi_bad)}"


def _sweep_tables(rows: list[SweepRow]) -> list[str]:
    lines = []
    moved = [r for r in rows if r.kind == "moved"]
    if moved:
        offsets = sorted({r.value for r in moved})
        lines += [("Moved by (v, v, v): each renderer against its own render of the scene at the origin "
                   "(ok = consistent at alpha 0.01 Holm, no NaN/Inf; the % is the image mean's change; "
                   "guard = what `check_precision` says)."), "",
                  "| scene (camera) | renderer | " + " | ".join(f"{v:g}" for v in offsets) + " |",
                  "|---|---|" + "---|" * len(offsets)]
        for key in dict.fromkeys((r.scene, r.camera) for r in moved):
            for who in ("mcrt", "mitsuba", "guard"):
                cells = []
                for v in offsets:
                    sel = [r for r in moved if (r.scene, r.camera) == key and r.value == v and r.renderer == ("mcrt" if who == "guard" else who)]
                    if not sel:
                        cells.append("")
                    elif who == "guard":
                        cells.append(f"{'accept' if sel[0].guard_ok else 'refuse'} ({sel[0].guard_ratio:.2g})")
                    else:
                        cells.append(f"{'ok' if sel[0].passed else 'WRONG'} {100 * sel[0].mean_rel_diff:+.1f} %")
                lines.append(f"| {key[0]} ({key[1]}) | {who} | " + " | ".join(cells) + " |")
        lines.append("")
    scaled = [r for r in rows if r.kind == "scaled"]
    if scaled:
        factors = sorted({r.value for r in scaled})
        lines += ["Scaled by v about the origin, cameras included:", "",
                  "| scene (camera) | renderer | " + " | ".join(f"{v:g}" for v in factors) + " |",
                  "|---|---|" + "---|" * len(factors)]
        for who in ("mcrt", "mitsuba", "mitsuba (default clips)", "guard"):
            cells = []
            for v in factors:
                sel = [r for r in scaled if r.value == v and r.renderer == ("mcrt" if who == "guard" else who)]
                if not sel:
                    cells.append("")
                elif who == "guard":
                    cells.append("accept" if sel[0].guard_ok else "refuse")
                else:
                    s = sel[0]
                    if s.nonfinite < 0:
                        cells.append("failed to render")
                    else:
                        cells.append(("ok" if s.passed else "WRONG") + (f" {s.nonfinite} NaN/Inf" if s.nonfinite else f" {100 * s.mean_rel_diff:+.1f} %"))
            lines.append(f"| {scaled[0].scene} ({scaled[0].camera}) | {who} | " + " | ".join(cells) + " |")
        lines.append("")
    return lines


def _convergence_table(rows: list[ConvergenceRow]) -> list[str]:
    spps = sorted({r.spp for r in rows})
    lines = ["| case | renderer | " + " | ".join(f"{n} spp" for n in spps) + " | slope |", "|---|---|" + "---|" * (len(spps) + 1)]
    for key in dict.fromkeys((r.case, r.renderer) for r in rows):
        cells = []
        for n in spps:
            sel = [r for r in rows if (r.case, r.renderer) == key and r.spp == n]
            cells.append(f"{sel[0].median_rel_rmse:.3g} ({sel[0].passed}/{sel[0].renders} ok, t {sel[0].median_worst_t:+.1f}, "
                         f"{sel[0].seconds:.2f} s)" if sel else "")
        lines.append(f"| {key[0]} | {key[1]} | " + " | ".join(cells) + f" | {convergence_slope(rows, *key):+.2f} |")
    return lines


def report_markdown(results: list[CaseResult], *, command: str, prov: dict[str, Any], settings: dict[str, Any],
                    sweep: list[SweepRow] | None = None, conv: list[ConvergenceRow] | None = None) -> str:
    """index.md: the method, the case table, the failures, the float32 limits and the convergence table."""
    res, spp, ref_spp = settings["res"], settings["spp"], settings["ref_spp"]
    v = prov["versions"]
    lines = [
        "# Hard cases: numerical stability of mcrt and Mitsuba 3", "",
        f"Command: `{command}`  ",
        (f"mcrt {v['mcrt']}, Mitsuba {v['mitsuba']}, Dr.Jit {v['drjit']}, Python {v['python']}, "
         f"{prov['drjit_threads']} threads on {prov['machine']['cpu']}, {prov['date']}"
         + (f", commit {prov['git_commit']}" if prov.get("git_commit") else "") + ".  "),
        (f"Seeds: mcrt {SEEDS['mcrt']}, Mitsuba {SEEDS['mitsuba']}, Mitsuba at equal time {SEEDS['mitsuba_equal_time']}, "
         f"reference {SEEDS['reference']}. Scenes: reference/scenes/hard/ (format 1) and the canonical scene transformed "
         "by `Scene.scaled(factor, offset)`."), "",
        (f"Each case is rendered at {res}x{res} by mcrt and Mitsuba (`path`, max depth 8) at N = {spp} spp each, by "
         f"Mitsuba again at equal time (@T: the spp it traces in mcrt's render time, JIT excluded), and by Mitsuba at "
         f"{ref_spp} spp as the reference of the error columns (for scaled and moved cases, from the untransformed "
         f"scene: the expected image is unchanged). Agreement: `mcrt.stats.compare_images` (Welch per {TILE}x{TILE} tile "
         f"and channel, each side's own variance, Holm at {ALPHA}); against the reference (\"image unchanged\"), the "
         "render's per-sample variance is floored at the reference's (`mcrt.stats.floor_variance`: without it a "
         "modest render false-alarms against a high-spp reference far more often than alpha, reports/validation/). "
         "rel. RMSE = RMSE against the reference / the reference's image mean; the reference's own noise adds to it "
         "(data.json: reference_noise). Times are render seconds without JIT compilation."), "",
        "## Cases", "",
        "| case | what it stresses |", "|---|---|",
        *[f"| {r.name} | {r.sentence} |" for r in results], "",
        *case_table(results), "",
    ]
    failing = [r for r in results if not r.passed]
    if failing:
        lines += ["## Failures", ""]
        for r in failing:
            lines.append(f"- **{r.name}**: " + "; ".join(r.problems))
            if r.known_issue:
                lines.append(f"  Known issue: {r.known_issue}.")
        lines.append("")
    refused = [r for r in results if r.expect == "refused"]
    for r in refused:
        lines += [f"Guard on {r.name}: {r.guard['message'] or 'accepted'}", ""]
    if sweep:
        lines += ["## Float32 limits", "", *_sweep_tables(sweep)]
        lines += ["Limits (largest value rendered right, first value rendered wrong):", ""]
        for lim in sweep_limits(sweep):
            lines.append(f"- {lim['scene']} ({lim['camera']}), {lim['kind']}, {lim['renderer']}: " + _limit_text(lim))
        lines.append("")
    if conv:
        n = conv[0].renders
        lines += ["## Fireflies and convergence", "",
                  (f"{n} independent renders per budget at {CONVERGENCE_RES}x{CONVERGENCE_RES} against a "
                   f"{CONVERGENCE_REF_SPP}-spp Mitsuba reference of the case: median relative RMSE, how many renders are "
                   f"consistent with the reference (alpha {ALPHA} Holm), the median signed t of the worst tile, median render "
                   "seconds, and the slope of log RMSE against log spp (-0.5 when the per-sample variance is finite)."), "",
                  *_convergence_table(conv), ""]
    lines += ["Images (mcrt, Mitsuba, reference; tone-mapped): " + ", ".join(f"[{r.name}]({r.name}.png)" for r in results), ""]
    return "\n".join(lines)


def write(path: Path, text: str) -> Path:
    path = Path(path)
    path.write_text(text, encoding="utf-8")
    return path
