"""Headless Chromium screenshots for the playback tests."""

from __future__ import annotations

import os
import shutil
import subprocess
import tempfile
from pathlib import Path

import numpy as np
import pytest

FLAGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--use-angle=swiftshader",
    "--enable-unsafe-swiftshader",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--hide-scrollbars",
    "--window-size=800,600",
]


def chromium() -> str:
    exe = shutil.which("chromium") or shutil.which("chromium-browser")
    if exe is None:
        if os.environ.get("CI") or os.environ.get("FREEFLOAT_REQUIRE_BROWSER"):
            pytest.fail("chromium is required for the browser tests (apt-get install chromium)")
        pytest.skip("chromium not installed (apt-get install chromium)")
    return exe


def screenshot(page: Path, virtual_ms: int, attempts: int = 3) -> np.ndarray:
    """RGB pixels of ``page`` after ``virtual_ms`` of virtual (page) time.

    Headless Chromium with its software renderer now and then never exits on a large meshed
    page (seen on unchanged pages too, the same page rendering in seconds the next time): a run
    that has not ended in 120 s is stopped and made again in a fresh profile, ``attempts``
    times at most. A page that never renders still fails. The profile's folder is removed
    without failing the test where Chromium's helper processes still write to it as they
    end (``Directory not empty: 'Default'``, once in a CI run).
    """
    from PIL import Image

    for attempt in range(1, attempts + 1):
        with tempfile.TemporaryDirectory(ignore_cleanup_errors=True) as tmp:
            out = Path(tmp) / "shot.png"
            try:
                subprocess.run(
                    [
                        chromium(),
                        *FLAGS,
                        f"--user-data-dir={tmp}/profile",
                        f"--virtual-time-budget={virtual_ms}",
                        f"--screenshot={out}",
                        page.as_uri(),
                    ],
                    check=True,
                    capture_output=True,
                    timeout=120,
                )
            except subprocess.TimeoutExpired:
                if attempt < attempts:
                    continue
                raise
            return np.asarray(Image.open(out).convert("RGB")).astype(int)
    raise ValueError(f"attempts must be >= 1, got {attempts}")
