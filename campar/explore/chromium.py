"""The headless Chromium that the explorer's browser tests and benchmark drive.

Debian's ``chromium`` package (``.ci/run`` installs it), never a browser Playwright
would download: these flags keep it from reaching any server but the explorer's.
"""

CHROMIUM = "/usr/bin/chromium"
CHROMIUM_ARGS = (
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-background-networking",
    "--disable-component-update",
    "--no-first-run",
    "--disable-sync",
)
