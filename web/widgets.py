"""Widget helpers the page's tabs share."""

from __future__ import annotations

from typing import Any


def masked_input_style(handle: Any) -> str:
    """CSS that draws a text input's characters as dots (Chromium, Firefox, Safari): viser has
    no password input. The field is found by its label's 'for', which is the input's uuid."""
    uuid = handle._impl.uuid  # viser labels an input with for="<uuid>"
    return (
        "<style>"
        f'div:has(> div > p > label[for="{uuid}"]) input '
        "{ -webkit-text-security: disc; }"
        "</style>"
    )
