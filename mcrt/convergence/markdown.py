"""index.md: the report as Markdown, images linked beside it."""

from __future__ import annotations

from pathlib import Path

from mcrt.convergence.content import Block


def _text(t: str) -> str:
    if t.startswith("**"):
        head, _, rest = t[2:].partition("**")
        return f"**{_esc(head)}**{_esc(rest)}"
    return _esc(t)


def _esc(t: str) -> str:
    return t.replace("|", "\\|").replace("<", "&lt;").replace(">", "&gt;").replace("*", "\\*").replace("_", "\\_")


def _table(header: list[str], rows: list[list[str]]) -> list[str]:
    out = ["| " + " | ".join(_esc(h) for h in header) + " |", "|" + "---|" * len(header)]
    out += ["| " + " | ".join(_esc(str(c)) for c in row) + " |" for row in rows]
    return out


def render(doc: list[Block]) -> str:
    out: list[str] = []
    for b in doc:
        kind = b[0]
        if kind == "h":
            out += ["#" * b[1] + " " + b[2], ""]
        elif kind == "p":
            out += [_text(b[1]), ""]
        elif kind == "ul":
            out += [f"- {_text(x)}" for x in b[1]] + [""]
        elif kind == "table":
            out += _table(b[1], b[2]) + [""]
        elif kind == "img":
            out += [f"![{b[2]}]({b[1]})", ""]
        elif kind == "link":
            out += [f"[{_esc(b[2])}: {_esc(b[1])}]({b[1]})", ""]
        elif kind == "code":
            out += ["```", b[1], "```", ""]
        elif kind == "details":
            out += ["<details><summary>" + _esc(b[1]) + "</summary>", ""]
            out += render(b[2]).splitlines() + ["", "</details>", ""]
        else:
            raise ValueError(f"unknown block {kind!r}")
    return "\n".join(out).rstrip() + "\n"


def write(path: Path, doc: list[Block]) -> Path:
    Path(path).write_text(render(doc), encoding="utf-8")
    return Path(path)
