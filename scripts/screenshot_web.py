"""Save a picture of the live web view in the middle of the demo's day (see scripts/screenshot-web).

The demo's scripted day runs up to the user's second fall, with the robot unable to call
support (so its obligations stay in force), then the virtual clock moves on 4 seconds: the
page shows the context with ages, each rule's layer, the latest decisions and why, two
countdowns (one nearly due), a prohibition, a violation and a refused action.
"""

from __future__ import annotations

import sys
from pathlib import Path

from playwright.sync_api import sync_playwright

from cosleec.demo import run
from cosleec.demo.assistive_care.scenario import STEPS
from cosleec.runtime import Manager, VirtualClock
from cosleec.testing import CHROMIUM, CHROMIUM_ARGS
from cosleec.views import AttachedView

ARGS = list(CHROMIUM_ARGS)
FALL = next(i for i, (kind, arg, _) in enumerate(STEPS) if kind == "event" and arg == "UserFallen")
SECOND_FALL = next(i for i in range(FALL + 1, len(STEPS)) if STEPS[i][1] == "UserFallen")
DAY = [
    *STEPS[:FALL],
    ("fail", "CallSupport", "the robot cannot reach support"),
    *STEPS[FALL : SECOND_FALL + 1],
    ("event", "MedicationDue", "time for the pills"),
    ("advance", 4, "four seconds later"),
]


def shoot(manager: Manager, url: str | None, out: Path) -> None:
    """Open the page at ``url`` in headless Chromium once it shows the Manager's last state, and save it."""
    assert isinstance(manager.clock, VirtualClock) and url
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=ARGS, headless=True)
        try:
            page = browser.new_page(viewport={"width": 1440, "height": 1000}, device_scale_factor=1)
            page.goto(url)
            page.wait_for_function("document.body.dataset.version !== undefined")
            page.wait_for_selector(".obligation[data-deadline]")
            page.wait_for_timeout(300)  # a heartbeat: the countdowns show the virtual clock's time
            out.parent.mkdir(parents=True, exist_ok=True)
            page.screenshot(path=str(out), full_page=True)
        finally:
            browser.close()


def main() -> int:
    """Run the day with the view and save the picture to the path given (argv[1])."""
    out = Path(sys.argv[1])
    web = AttachedView(0)  # the web view on a free port: the demo attaches it before its Manager starts
    run(DAY, view=web.attach, before_close=lambda m: shoot(m, web.url, out))
    print(f"saved {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
