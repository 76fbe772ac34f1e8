"""index.html: the report as one self-contained HTML file (PNG images embedded as base64 data URIs).

It needs no network, no script and no file beside it: it opens in any browser
from anywhere.
"""

from __future__ import annotations

import base64
from html import escape
from pathlib import Path

from mcrt.convergence.content import Block

STYLE = """
body { font-family: system-ui, -apple-system, "Segoe UI", Helvetica, Arial, sans-serif; margin: 2em auto; max-width: 1150px;
       padding: 0 1em; color: #222; line-height: 1.45; }
h1 { font-size: 1.6em; } h2 { font-size: 1.25em; margin-top: 1.8em; border-bottom: 1px solid #ddd; }
table { border-collapse: collapse; font-size: 0.82em; margin: 0.6em 0 1em; }
th, td { border: 1px solid #ccc; padding: 0.2em 0.5em; text-align: right; white-space: nowrap; }
th { background: #f3f3f3; } td:first-child, th:first-child { text-align: left; }
img { max-width: 100%; height: auto; display: block; margin: 0.6em 0; }
figure { margin: 0.5em 0 1.2em; } figcaption { font-size: 0.85em; color: #555; }
.scroll { overflow-x: auto; } details { margin: 1em 0; } li { margin: 0.2em 0; }
"""


def _text(t: str) -> str:
    if t.startswith("**"):
        head, _, rest = t[2:].partition("**")
        return f"<strong>{escape(head)}</strong>{escape(rest)}"
    return escape(t)


def _data_uri(path: Path) -> str:
    return "data:image/png;base64," + base64.b64encode(Path(path).read_bytes()).decode("ascii")


def _render(doc: list[Block], folder: Path) -> list[str]:
    out: list[str] = []
    for b in doc:
        kind = b[0]
        if kind == "h":
            out.append(f"<h{b[1]}>{escape(b[2])}</h{b[1]}>")
        elif kind == "p":
            out.append(f"<p>{_text(b[1])}</p>")
        elif kind == "ul":
            out.append("<ul>" + "".join(f"<li>{_text(x)}</li>" for x in b[1]) + "</ul>")
        elif kind == "table":
            head = "".join(f"<th>{escape(h)}</th>" for h in b[1])
            body = "".join("<tr>" + "".join(f"<td>{escape(str(c))}</td>" for c in row) + "</tr>" for row in b[2])
            out.append(f'<div class="scroll"><table><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table></div>')
        elif kind == "img":
            out.append(f'<figure><img src="{_data_uri(folder / b[1])}" alt="{escape(b[2])}"><figcaption>{escape(b[2])} ({escape(b[1])})</figcaption></figure>')
        elif kind == "link":  # a file beside the report: named, not linked, so the page has no outside reference
            out.append(f"<p>{escape(b[2])}: {escape(b[1])} (beside this file)</p>")
        elif kind == "code":
            out.append(f"<pre>{escape(b[1])}</pre>")
        elif kind == "details":
            out.append(f"<details><summary>{escape(b[1])}</summary>" + "".join(_render(b[2], folder)) + "</details>")
        else:
            raise ValueError(f"unknown block {kind!r}")
    return out


def render(doc: list[Block], folder: Path) -> str:
    title = next((b[2] for b in doc if b[0] == "h" and b[1] == 1), "mcrt report")
    body = "\n".join(_render(doc, Path(folder)))
    return (f'<!DOCTYPE html>\n<html lang="en">\n<head>\n<meta charset="utf-8">\n'
            f'<meta name="viewport" content="width=device-width, initial-scale=1">\n'
            f"<title>{escape(title)}</title>\n<style>{STYLE}</style>\n</head>\n<body>\n{body}\n</body>\n</html>\n")


def write(path: Path, doc: list[Block]) -> Path:
    """Write the HTML; images named in ``doc`` are read from the folder of ``path`` and embedded."""
    path = Path(path)
    path.write_text(render(doc, path.parent), encoding="utf-8")
    return path
