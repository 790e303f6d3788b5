"""How cosleec's browser tests and pictures start Chromium: Debian's, headless, offline.

Playwright drives the system browser (it downloads none). The flags keep Chromium from
reaching for the network at start (background networking, component updates, sync), which
a closed network refuses many times over; ``--no-sandbox`` because CI runs as root.
"""

from __future__ import annotations

CHROMIUM = "/usr/bin/chromium"
"""Debian's Chromium (``scripts/setup --dev`` installs it as root)."""

CHROMIUM_ARGS = (
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
)
"""The flags to launch it with: ``p.chromium.launch(executable_path=CHROMIUM, args=list(CHROMIUM_ARGS))``."""
