"""The report page: one self-contained HTML file (CSS inline, every image base64-embedded),
built from the report's JSON data and its PNG images."""

from __future__ import annotations

import base64
import html
import math
from typing import Callable, Dict, List, Optional, Sequence, Tuple

Column = Tuple[str, str, Callable[[object], str]]  # (key, heading, formatter)

CSS = """
body { font-family: sans-serif; max-width: 1200px; margin: 1em auto; padding: 0 1em; color: #222; }
h1 { font-size: 1.6em; } h2 { border-bottom: 1px solid #ccc; margin-top: 2em; } h3 { margin-bottom: .3em; }
table { border-collapse: collapse; font-size: 12px; margin: .5em 0 1em; }
th, td { border: 1px solid #ccc; padding: 2px 6px; text-align: right; }
th { background: #f0f0f0; } td.l, th.l { text-align: left; }
tr.front td { background: #fff4cc; }
.pass { color: #060; font-weight: bold; } .fail { color: #a00; font-weight: bold; }
.note { color: #555; font-size: 13px; } .finding { background: #eef5ff; padding: .4em .8em; border-left: 4px solid #48c; }
figure { display: inline-block; margin: .4em 1em .8em 0; vertical-align: top; max-width: 100%; }
img { max-width: 100%; height: auto; }
figcaption { font-size: 12px; color: #444; max-width: 760px; }
img.px { image-rendering: pixelated; }
nav a { margin-right: 1em; font-size: 13px; }
"""


def num(spec: str, scale: float = 1.0, unit: str = "") -> Callable[[object], str]:
    def fmt(value) -> str:
        if value is None or (isinstance(value, float) and math.isnan(value)):
            return "n/a"
        if isinstance(value, float) and math.isinf(value):
            return "∞"
        return f"{value * scale:{spec}}{unit}"
    return fmt


def text(value) -> str:
    if isinstance(value, (list, tuple)):
        return "×".join(str(v) for v in value) if all(isinstance(v, int) for v in value) else \
            "(" + ", ".join(f"{v:.3f}" if isinstance(v, float) else str(v) for v in value) + ")"
    if isinstance(value, bool):
        return "yes" if value else "no"
    return "" if value is None else str(value)


def esc(value: str) -> str:
    return html.escape(value, quote=True)


def table(rows: Sequence[Dict[str, object]], columns: Sequence[Column],
          highlight: Optional[Callable[[Dict[str, object]], bool]] = None) -> str:
    head = "".join(f'<th class="{"l" if f is text else ""}">{esc(h)}</th>' for _, h, f in columns)
    body = []
    for row in rows:
        cls = ' class="front"' if highlight is not None and highlight(row) else ""
        cells = "".join(f'<td class="{"l" if f is text else ""}">{esc(f(row.get(k)))}</td>' for k, _, f in columns)
        body.append(f"<tr{cls}>{cells}</tr>")
    return f"<table><tr>{head}</tr>{''.join(body)}</table>"


def image(png: bytes, caption: str, width: Optional[int] = None, pixelated: bool = False) -> str:
    data = base64.b64encode(png).decode("ascii")
    size = f' width="{width}"' if width else ""
    cls = ' class="px"' if pixelated else ""
    return (f'<figure><img{cls}{size} src="data:image/png;base64,{data}" alt="{esc(caption)}">'
            f"<figcaption>{esc(caption)}</figcaption></figure>")


class Page:
    """Collects sections; `render()` gives the HTML text."""

    def __init__(self, title: str):
        self.title = title
        self.parts: List[str] = []
        self.toc: List[Tuple[str, str]] = []

    def section(self, anchor: str, heading: str) -> None:
        self.toc.append((anchor, heading))
        self.parts.append(f'<h2 id="{esc(anchor)}">{esc(heading)}</h2>')

    def add(self, markup: str) -> None:
        self.parts.append(markup)

    def paragraph(self, words: str, cls: str = "") -> None:
        attr = f' class="{cls}"' if cls else ""
        self.parts.append(f"<p{attr}>{esc(words)}</p>")

    def render(self) -> str:
        nav = "".join(f'<a href="#{esc(a)}">{esc(h)}</a>' for a, h in self.toc)
        return ("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
                f"<title>{esc(self.title)}</title><style>{CSS}</style></head><body>"
                f"<h1>{esc(self.title)}</h1><nav>{nav}</nav>{''.join(self.parts)}</body></html>\n")
