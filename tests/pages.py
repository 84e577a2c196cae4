"""Reading the reports' HTML in tests: the first table of a page."""

from __future__ import annotations

import html
import re

__all__ = ["first_table"]


def _text(cell: str) -> str:
    return html.unescape(re.sub(r"<[^>]+>", "", cell)).strip()


def first_table(page: str) -> tuple[list[str], list[list[str]]]:
    """Headers and cell texts (tags stripped, entities decoded) of a page's first table."""
    body = page.split("<table", 1)[1].split("</table>", 1)[0]
    headers = [_text(h) for h in re.findall(r"<th[^>]*>(.*?)</th>", body, re.S)]
    rows = [[_text(c) for c in re.findall(r"<td[^>]*>(.*?)</td>", r, re.S)]
            for r in re.findall(r"<tr>(.*?)</tr>", body.split("<tbody>", 1)[1], re.S)]
    return headers, rows
