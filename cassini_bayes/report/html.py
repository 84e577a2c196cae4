"""Self-contained HTML pages: one inline style sheet, figures as ``data:`` URIs, nothing external.

The building blocks here are shared by the per-run diagnostic report (:mod:`cassini_bayes.report`)
and by the one-page ``reproduce`` summary, so every page of the package looks the same:

>>> page = html_page("Run", [section("Diagnostics", table(["a", "b"], [[1, 2]]))])

Every function returns an HTML *fragment* (a ``str``) except :func:`html_page`, which returns the
whole document. Text arguments are escaped here (``html.escape``); arguments documented as HTML
(``body``, table cells wrapped in :class:`Raw`) are inserted as they are.
"""

from __future__ import annotations

import base64
import html
from collections.abc import Iterable, Sequence
from dataclasses import dataclass


__all__ = [
    "GENERATOR",
    "written_by_package",
    "Raw",
    "Section",
    "section",
    "html_page",
    "table",
    "figure",
    "badge",
    "paragraph",
    "bullet_list",
    "link",
    "not_available",
    "details",
    "page_header",
    "meta_list",
    "preformatted",
    "esc",
]

STYLE = """
body { font-family: system-ui, -apple-system, "Segoe UI", Helvetica, Arial, sans-serif;
       margin: 0 auto; max-width: 1320px; padding: 0 1.2em 3em; color: #1d2330; background: #fff;
       line-height: 1.45; }
header { border-bottom: 2px solid #2b4a7a; margin-bottom: 1em; padding: 0.8em 0 0.6em; }
h1 { font-size: 1.55em; margin: 0.2em 0; color: #2b4a7a; }
h2 { font-size: 1.2em; margin: 1.6em 0 0.5em; padding-bottom: 0.2em;
     border-bottom: 1px solid #d5dbe5; color: #2b4a7a; }
h3 { font-size: 1.0em; margin: 1.1em 0 0.4em; }
nav { font-size: 0.9em; margin: 0.4em 0; }
nav a { margin-right: 0.9em; color: #2b4a7a; text-decoration: none; }
nav a:hover { text-decoration: underline; }
dl.meta { display: grid; grid-template-columns: max-content auto; gap: 0.1em 1em; margin: 0.5em 0;
          font-size: 0.92em; }
dl.meta dt { font-weight: 600; color: #4a5568; }
dl.meta dd { margin: 0; font-family: ui-monospace, Menlo, Consolas, monospace;
             word-break: break-all; }
div.tbl { overflow-x: auto; max-width: 100%; }
table { border-collapse: collapse; margin: 0.4em 0 1em; font-size: 0.88em; }
th, td { border: 1px solid #d5dbe5; padding: 0.25em 0.6em; text-align: right; white-space: nowrap; }
th { background: #eef2f8; text-align: center; white-space: normal; }
td.l, th.l { text-align: left; }
td.w { white-space: normal; min-width: 9em; max-width: 30em; text-align: left; }
table.fit { width: 100%; }
p.verdicts { margin: 0.5em 0 0.2em; }
p.verdicts .badge { font-size: 0.95em; padding: 0.2em 0.8em; }
p.meta { margin: 0.2em 0; font-size: 0.85em; color: #4a5568; }
tr:nth-child(even) td { background: #fafbfd; }
td.bad { background: #fde2e1 !important; color: #8a1c14; font-weight: 600; }
td.warn { background: #fff4d6 !important; color: #7a5200; }
td.good { color: #1f6b34; }
.badge { display: inline-block; padding: 0.15em 0.7em; border-radius: 1em; font-size: 0.85em;
         font-weight: 700; letter-spacing: 0.02em; vertical-align: middle; }
.badge.ok { background: #d8f0de; color: #1f6b34; border: 1px solid #9ccfab; }
.badge.fail { background: #fde2e1; color: #8a1c14; border: 1px solid #f0a8a3; }
.badge.info { background: #e6ecf6; color: #2b4a7a; border: 1px solid #b7c6df; }
.warnings { background: #fff8e6; border-left: 4px solid #e0a100; padding: 0.4em 1em;
            margin: 0.8em 0; }
.warnings ul { margin: 0.2em 0; padding-left: 1.2em; }
.na { color: #6b7280; font-style: italic; }
figure { margin: 0.6em 0 1.2em; }
figure img { max-width: 100%; height: auto; border: 1px solid #e5e9f0; }
figcaption { font-size: 0.86em; color: #4a5568; margin-top: 0.3em; max-width: 60em; }
pre { background: #f5f7fa; border: 1px solid #e1e6ee; padding: 0.6em; overflow-x: auto;
      font-size: 0.82em; }
details summary { cursor: pointer; color: #2b4a7a; }
p.note { font-size: 0.88em; color: #4a5568; max-width: 60em; }
footer { margin-top: 2.5em; font-size: 0.8em; color: #6b7280; border-top: 1px solid #e5e9f0;
         padding-top: 0.5em; }
"""


class Raw(str):
    """A string that is already HTML: :func:`table` inserts it without escaping."""


def esc(text: object) -> str:
    """Escape any object's ``str`` for HTML text or attribute values."""
    return html.escape(str(text), quote=True)


@dataclass(frozen=True)
class Section:
    """One ``<section>`` of a page.

    Attributes
    ----------
    title : str
        Heading text (escaped).
    body : str
        HTML fragment (inserted as is).
    id : str
        Anchor used by the page's navigation bar.
    """

    title: str
    body: str
    id: str


def _slug(text: str) -> str:
    out = "".join(c.lower() if c.isalnum() else "-" for c in text)
    return "-".join(p for p in out.split("-") if p) or "section"


def section(title: str, body: str | Iterable[str], *, id: str | None = None) -> Section:
    """Make a :class:`Section`; ``body`` is one HTML fragment or several joined in order."""
    if not isinstance(body, str):
        body = "\n".join(body)
    return Section(title=title, body=body, id=id or _slug(title))


GENERATOR = '<meta name="generator" content="cassini-bayes">'


def written_by_package(path) -> bool:
    """Whether the file at ``path`` is an HTML page this package wrote (its generator tag, or
    the ``cassini-bayes`` title of pages written before the tag), so that ``--force`` may
    replace it."""
    try:
        with open(path, "rb") as fh:
            head = fh.read(4096).decode("utf-8", "replace")
    except OSError:
        return False
    return GENERATOR in head or "<title>cassini-bayes " in head


def html_page(
    title: str,
    sections: Sequence[Section],
    *,
    header: str = "",
    footer: str = "",
    nav: bool = True,
) -> str:
    """A complete, self-contained HTML document.

    Parameters
    ----------
    title : str
        Page title and ``<h1>`` text (escaped).
    sections : sequence of Section
        Sections in page order; each gets an ``<h2>`` and an entry in the navigation bar.
    header : str
        HTML fragment shown under the title (metadata, badges, warnings).
    footer : str
        HTML fragment shown at the bottom.
    nav : bool
        Whether to show a navigation bar linking to the sections.

    Returns
    -------
    str
        The document; it loads no external resource (inline CSS, figures as ``data:`` URIs).
    """
    nav_html = ""
    if nav and sections:
        nav_html = "<nav>" + "".join(
            f'<a href="#{esc(s.id)}">{esc(s.title)}</a>' for s in sections
        ) + "</nav>"
    body = "\n".join(
        f'<section id="{esc(s.id)}">\n<h2>{esc(s.title)}</h2>\n{s.body}\n</section>'
        for s in sections
    )
    foot = f"<footer>{footer}</footer>" if footer else ""
    return (
        "<!DOCTYPE html>\n"
        '<html lang="en">\n<head>\n<meta charset="utf-8">\n'
        '<meta name="viewport" content="width=device-width, initial-scale=1">\n'
        f"{GENERATOR}\n<title>{esc(title)}</title>\n<style>{STYLE}</style>\n</head>\n<body>\n"
        f"<header>\n<h1>{esc(title)}</h1>\n{header}\n{nav_html}\n</header>\n"
        f"{body}\n{foot}\n</body>\n</html>\n"
    )


def table(
    headers: Sequence[str],
    rows: Iterable[Sequence[object]],
    *,
    left: int = 1,
    classes: Iterable[Sequence[str]] | None = None,
    fit: bool = False,
) -> str:
    """An HTML table.

    Parameters
    ----------
    headers : sequence of str
        Column headings (escaped).
    rows : iterable of sequences
        Cell values; :class:`Raw` cells are inserted as HTML, anything else is escaped.
    left : int
        Number of leading columns aligned left (labels); the rest are right-aligned numbers.
    classes : iterable of sequences of str, optional
        Per-cell CSS classes (``"bad"``, ``"warn"``, ``"good"``; ``"w"``: a text cell that
        wraps), same shape as ``rows``.

    fit : bool
        Fit the page's width, the wrapping cells (class ``"w"``) taking what is left: for a
        table of long text.

    The table sits in a box that scrolls sideways when it is wider than the page: nothing is
    ever cut off.
    """
    rows = [list(r) for r in rows]
    cls = [list(c) for c in classes] if classes is not None else [[""] * len(r) for r in rows]
    head = "".join(
        f'<th class="l">{esc(h)}</th>' if i < left else f"<th>{esc(h)}</th>"
        for i, h in enumerate(headers)
    )
    table_cls = ' class="fit"' if fit else ""
    out = [f'<div class="tbl"><table{table_cls}>\n<thead><tr>{head}</tr></thead>\n<tbody>']
    for r, c in zip(rows, cls, strict=True):
        cells = []
        for i, v in enumerate(r):
            extra = c[i] if i < len(c) else ""
            names = " ".join(x for x in ("l" if i < left else "", extra) if x)
            attr = f' class="{names}"' if names else ""
            text = v if isinstance(v, Raw) else esc(v)
            cells.append(f"<td{attr}>{text}</td>")
        out.append("<tr>" + "".join(cells) + "</tr>")
    out.append("</tbody>\n</table></div>")
    return "\n".join(out)


def figure(png: bytes, caption: str = "", *, alt: str = "") -> str:
    """A figure embedded as a base64 ``data:image/png`` URI, with an escaped caption."""
    data = base64.b64encode(png).decode("ascii")
    cap = f"<figcaption>{esc(caption)}</figcaption>" if caption else ""
    return (
        f'<figure><img src="data:image/png;base64,{data}" alt="{esc(alt or caption)}">'
        f"{cap}</figure>"
    )


def badge(text: str, ok: bool | None) -> str:
    """A pill badge: green when ``ok``, red when not, neutral blue when ``None``."""
    kind = "info" if ok is None else ("ok" if ok else "fail")
    return f'<span class="badge {kind}">{esc(text)}</span>'


def paragraph(text: str, *, note: bool = False) -> str:
    """A paragraph of escaped text (``note=True``: small grey explanatory text)."""
    return f'<p class="note">{esc(text)}</p>' if note else f"<p>{esc(text)}</p>"


def bullet_list(items: Iterable[str], *, raw: bool = False) -> str:
    """An unordered list of escaped items (``raw=True``: items are HTML fragments)."""
    lis = "".join(f"<li>{i if raw else esc(i)}</li>" for i in items)
    return f"<ul>{lis}</ul>"


def link(href: str, text: str) -> str:
    """A link, e.g. a relative link from a summary page to a run's ``report.html``."""
    return f'<a href="{esc(href)}">{esc(text)}</a>'


def not_available(what: str) -> str:
    """The standard "not available" line for a section whose data the run does not have."""
    return f'<p class="na">Not available: {esc(what)}</p>'


def meta_list(pairs: Iterable[tuple[str, object]]) -> str:
    """A two-column "key: value" list (run metadata under a page title); both escaped."""
    items = "".join(f"<dt>{esc(k)}</dt><dd>{esc(v)}</dd>" for k, v in pairs)
    return f'<dl class="meta">{items}</dl>'


def details(summary: str, body: str) -> str:
    """A collapsible block: escaped ``summary`` line, HTML ``body``."""
    return f"<details><summary>{esc(summary)}</summary>\n{body}\n</details>"


def page_header(badges: str, meta: str, warnings: Iterable[str] = ()) -> str:
    """The header every report opens with: the verdict ``badges`` (HTML), one line of escaped
    ``meta`` (command, version, sizes) and, when there are any, the ``warnings`` (escaped)."""
    warns = [str(w) for w in warnings]
    out = [f'<p class="verdicts">{badges}</p>', f'<p class="meta">{esc(meta)}</p>']
    if warns:
        out.append(f'<div class="warnings"><strong>Warnings</strong>{bullet_list(warns)}</div>')
    return "\n".join(out)


def preformatted(text: str) -> str:
    """Escaped text in a ``<pre>`` block (configuration files, logs)."""
    return f"<pre>{esc(text)}</pre>"
