"""The text reports of ``mcrt reference``: the ``list`` table and the ``verify`` verdicts."""

from __future__ import annotations

from typing import Any

from mcrt.groundtruth.spec import depth_label
from mcrt.groundtruth.verify import VerifyResult


def format_table(rows: list[dict[str, Any]]) -> str:
    """The ``mcrt reference list`` table."""
    head = ("reference", "camera", "size", "depth", "spp", "KiB", "rel.s.e.", "mitsuba", "variant", "render s", "built", "status")
    lines = [head]
    for r in rows:
        lines.append((
            r["key"], r["camera"], f"{r['width']}x{r['height']}", depth_label(r["max_depth"]), str(r["spp"]),
            f"{r.get('bytes', 0) / 1024:.0f}", f"{r.get('median_rel_std_error', float('nan')):.2%}",
            r["mitsuba_version"], r["variant"], f"{r.get('render_time_s', 0):.0f}", r.get("date", "")[:10], r["status"],
        ))
    widths = [max(len(str(line[i])) for line in lines) for i in range(len(head))]
    right = {4, 5, 6, 9}
    out = ["  ".join(str(c).rjust(wd) if i in right else str(c).ljust(wd) for i, (c, wd) in enumerate(zip(line, widths))).rstrip() for line in lines]
    out.insert(1, "  ".join("-" * wd for wd in widths))
    total = sum(r.get("bytes", 0) for r in rows)
    size = f"{total / 2**20:.1f} MiB" if total >= 2**20 else f"{total / 1024:.0f} KiB"
    out.append(f"{len(rows)} references, {size}; rel.s.e. = median relative standard error of a pixel's mean")
    for r in rows:
        if r["status"] != "ok":
            out.append(f"{r['key']}: {r['status']}: {r['detail']}")
    return "\n".join(out)



def format_verify(results: list[VerifyResult]) -> str:
    """The ``mcrt reference verify`` report: one block per reference, then a verdict line."""
    out = []
    for r in results:
        word = {"ok": "OK", "failed": "FAILED", "unusable": "UNUSABLE"}[r.status]
        out.append(f"{word:8s} {r.key}" + (f"  ({r.wall_time:.1f} s)" if r.wall_time else ""))
        out.extend(f"         {c}" for c in r.checks)
    n_ok = sum(r.passed for r in results)
    bad = [r.key for r in results if not r.passed]
    out.append(f"{n_ok} of {len(results)} references verified" + (f"; not verified: {', '.join(bad)}" if bad else ""))
    return "\n".join(out)
