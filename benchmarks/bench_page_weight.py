"""Bytes the browser fetches for the dashboard's first page (issue 27: target ≤ 2.0 MB).

Run: ``python benchmarks/bench_page_weight.py [--plain]``. Starts ``python -m dashboard.serve``
(gzip on, MathJax only for a formula; ``--plain``: ``panel serve dashboard/app.py --warm``) on
a free port, opens the page in headless Chromium, waits until the network is idle and prints
the bytes on the wire (Chrome DevTools' encodedDataLength) per response and in all.
"""

from __future__ import annotations

import socket
import subprocess
import sys
import time
import urllib.request
from pathlib import Path

from playwright.sync_api import sync_playwright

ROOT = Path(__file__).resolve().parent.parent
CHROMIUM_ARGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-background-networking",
    "--disable-component-update",
    "--no-first-run",
]
START_TIMEOUT_S = 300.0


def free_port() -> int:
    """A TCP port nothing listens on."""
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


def wait_for(url: str) -> None:
    """Return once the server answers ``url`` (it warms the kernels first)."""
    deadline = time.monotonic() + START_TIMEOUT_S
    while time.monotonic() < deadline:
        try:
            urllib.request.urlopen(url, timeout=5).close()
            return
        except OSError:
            time.sleep(1.0)
    raise TimeoutError(f"no answer from {url} within {START_TIMEOUT_S:g} s")


def fetched_bytes(url: str) -> list[tuple[int, str, str]]:
    """(bytes on the wire, URL, content encoding) of every response of the page."""
    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(
            executable_path="/usr/bin/chromium", args=CHROMIUM_ARGS
        )
        page = browser.new_page()
        devtools = page.context.new_cdp_session(page)
        devtools.send("Network.enable")
        responses, sizes = {}, {}

        def received(event) -> None:
            headers = {k.lower(): v for k, v in event["response"]["headers"].items()}
            responses[event["requestId"]] = (
                event["response"]["url"],
                headers.get("content-encoding", ""),
            )

        devtools.on("Network.responseReceived", received)
        devtools.on(
            "Network.loadingFinished",
            lambda event: sizes.__setitem__(event["requestId"], event["encodedDataLength"]),
        )
        page.goto(url, timeout=START_TIMEOUT_S * 1e3)
        page.wait_for_load_state("networkidle", timeout=START_TIMEOUT_S * 1e3)
        time.sleep(2.0)
        browser.close()
    return sorted(((int(sizes.get(key, 0)), *responses[key]) for key in responses), reverse=True)


def main() -> None:
    port = free_port()
    plain = "--plain" in sys.argv
    if plain:
        command = ["panel", "serve", "dashboard/app.py", "--warm"]
    else:
        command = [sys.executable, "-m", "dashboard.serve"]
    command += ["--port", str(port), "--address", "127.0.0.1"]
    server = subprocess.Popen(
        command, cwd=ROOT, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL
    )
    try:
        url = f"http://127.0.0.1:{port}/app"
        wait_for(url)
        rows = fetched_bytes(url)
    finally:
        server.terminate()
        server.wait(timeout=30)
    for size, address, encoding in rows[:12]:
        print(f"  {size / 1e3:8.1f} kB  {encoding or '-':5s} {address.split('?')[0]}")
    total = sum(size for size, _, _ in rows)
    label = "panel serve (plain)" if plain else "python -m dashboard.serve"
    print(f"{label}: {total / 1e6:.2f} MB in {len(rows)} responses (target ≤ 2.0 MB)")


if __name__ == "__main__":
    main()
