"""Links the Scores tab gives to the console's HTTP API: a recording's debrief report and its
logbook entry, each opening in a tab of its own. Both need a token, which a link cannot carry
as a header: for a browser unlocked with the console or instructor token they carry the
console's debrief ticket (``Console.debrief_ticket``) instead."""

from __future__ import annotations

import html
from urllib.parse import quote, urlencode


def _with_query(url: str, query: dict[str, str]) -> str:
    return url + (f"?{urlencode(query)}" if query else "")


def report_url(api_base: str, name: str, ticket: str | None = None) -> str:
    """The debrief's address; with the console's debrief ticket (``Console.debrief_ticket``)
    for a browser that is unlocked: the report needs a token, and a link carries no header."""
    url = f"{api_base}/api/recordings/{quote(name)}/report"
    return _with_query(url, {"ticket": ticket} if ticket else {})


def logbook_url(api_base: str, name: str, ticket: str | None = None, fmt: str = "pdf") -> str:
    """A recording's logbook entry, PDF or CSV (``fmt``), with the ticket as the debrief's."""
    query = {"format": "csv"} if fmt == "csv" else {}
    if ticket:
        query["ticket"] = ticket
    return _with_query(f"{api_base}/api/recordings/{quote(name)}/logbook", query)


def new_tab_link(url: str, text: str) -> str:
    """A link that opens in a tab of its own (HTML in the Markdown, which viser renders): the
    debrief replaced the console's tab, and coming back needed the token again."""
    return (
        f'<a href="{html.escape(url, quote=True)}" target="_blank" rel="noopener">'
        f"{html.escape(text)}</a>"
    )
