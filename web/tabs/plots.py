"""The plots, in a folder above the tabs (not a tab, and not below them: they stay in sight
whichever tab is open, the mission builder's long one too): the console's plots page
(``app.api.plots``) in an iframe. viser's uPlot handle re-sends its whole data at each
assignment (no append), 48 kB/s for two updates a second; the page gets the window once,
then only the new rows."""

from __future__ import annotations

import viser

from app.console import ConsoleSettings


def plots_url(settings: ConsoleSettings, client_id: int) -> str:
    """The plots page following this browser (its replay when it shows one)."""
    host = settings.host
    if host in ("0.0.0.0", "::"):  # a wildcard bind: the loopback name on this machine
        host = "127.0.0.1"
    host = f"[{host}]" if ":" in host else host
    return f"http://{host}:{settings.port}/plots?viewer={client_id}"


def add_plots(gui: viser.GuiApi, url: str) -> viser.GuiHtmlHandle:
    return gui.add_html(
        f'<iframe src="{url}" title="plots" '
        'style="width:100%;height:430px;border:0;display:block"></iframe>'
        f'<a href="{url}" target="_blank" rel="noopener" '
        'style="font-size:12px">open the plots in their own tab</a>'
    )
