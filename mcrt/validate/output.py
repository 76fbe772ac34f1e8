"""Writing a study's files: Markdown and JSON per study, and the folder's README."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import mcrt.validate.data as data
from mcrt.validate.markdown import false_alarm_markdown, power_markdown
from mcrt.validate.meta import report_meta
from mcrt.validate.readme import readme_root, write_readme

#: (key in the results, file stem, Markdown writer) of each study.
STUDIES = (("false_alarms", "false_alarms", false_alarm_markdown), ("power", "power", power_markdown))


def write_reports(results: dict[str, Any], out_dir: str | Path = "reports/validation", *, readme: bool = True) -> list[Path]:
    """Write the reports of :func:`false_alarm_study` / :func:`power_study` results.

    ``results`` holds ``meta`` (from :func:`mcrt.validate.report_meta`;
    without it the process's command line is recorded and the scene is not)
    and either or both of ``false_alarms`` and ``power``. Writes
    ``false_alarms.md`` and ``false_alarms.json``, ``power.md`` and
    ``power.json`` (each JSON file is the study's dict with the provenance
    under ``meta``), and with ``readme`` the README.md of the validation folder
    the run belongs to (:func:`mcrt.validate.readme.readme_root`). Returns the
    paths written.
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    meta = results.get("meta") or report_meta(None)
    written = []
    for key, stem, markdown in STUDIES:
        study = results.get(key)
        if study is None:
            continue
        (out / f"{stem}.md").write_text(markdown(study, meta), encoding="utf-8")
        written += [out / f"{stem}.md", data.write(out / f"{stem}.json", study, meta)]
    if readme:
        path = write_readme(readme_root(out))
        if path is not None:
            written.append(path)
    return written
