#!/usr/bin/env python3
"""Screenshot a page in headless Chromium through the DevTools protocol.

usage: cdp_screenshot.py URL OUT.png [--wait S] [--width W] [--height H] [--full-page]

Starts Chromium (SwiftShader WebGL, no GPU, no WebGPU), opens URL, waits S
seconds (the Rerun web viewer needs about a minute to load its wasm on these
machines), then captures with `Page.captureScreenshot` (`--full-page`: the whole page
once, up to 16 000 px, by making the viewport as tall as the page). Needs the Debian
`chromium` package and the `websocket-client` Python package.
"""
import argparse
import base64
import json
import os
import shutil
import socket
import subprocess
import sys
import tempfile
import time
import urllib.request

import websocket  # websocket-client


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("url")
    ap.add_argument("out")
    ap.add_argument("--wait", type=float, default=5.0)
    ap.add_argument("--width", type=int, default=1600)
    ap.add_argument("--height", type=int, default=1000)
    ap.add_argument("--full-page", action="store_true")
    a = ap.parse_args()

    browser = shutil.which("chromium") or shutil.which("chromium-browser")
    if not browser:
        sys.exit("error: chromium not found (apt-get install -y chromium)")
    port = free_port()
    profile = tempfile.mkdtemp(prefix="cdp-profile-")
    args = [
        browser,
        "--headless=new",
        "--no-sandbox",
        "--use-angle=swiftshader",
        "--enable-unsafe-swiftshader",
        "--ignore-gpu-blocklist",
        # SwiftShader's WebGPU crashes the Rerun viewer; WebGL only.
        "--disable-features=WebGPU,Vulkan",
        "--hide-scrollbars",
        f"--window-size={a.width},{a.height}",
        f"--remote-debugging-port={port}",
        # Chromium 111+ refuses DevTools websockets from other origins.
        "--remote-allow-origins=*",
        f"--user-data-dir={profile}",
        "about:blank",
    ]
    proc = subprocess.Popen(args, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        targets = None
        for _ in range(100):
            try:
                with urllib.request.urlopen(f"http://127.0.0.1:{port}/json/list") as r:
                    targets = [t for t in json.load(r) if t.get("type") == "page"]
                if targets:
                    break
            except OSError:
                pass
            time.sleep(0.2)
        if not targets:
            sys.exit("error: chromium DevTools endpoint did not come up")
        ws = websocket.create_connection(targets[0]["webSocketDebuggerUrl"], timeout=900)
        ids = iter(range(1, 1 << 30))

        def call(method, **params):
            i = next(ids)
            ws.send(json.dumps({"id": i, "method": method, "params": params}))
            while True:
                msg = json.loads(ws.recv())
                if msg.get("id") == i:
                    if "error" in msg:
                        raise RuntimeError(f"{method}: {msg['error']}")
                    return msg.get("result", {})

        call("Page.enable")
        call(
            "Emulation.setDeviceMetricsOverride",
            width=a.width,
            height=a.height,
            deviceScaleFactor=1,
            mobile=False,
        )
        call("Page.navigate", url=a.url)
        time.sleep(a.wait)
        params = {"format": "png"}
        if a.full_page:
            # Make the viewport as tall as the page and capture it as it is:
            # `captureBeyondViewport` with a clip taller than the window
            # repeated the page from the top after ~8 000 px. 16 000 px is
            # below the texture limit of Chromium's compositor.
            m = call("Page.getLayoutMetrics")
            size = m.get("cssContentSize") or m["contentSize"]
            tall = int(min(max(size["height"], a.height), 16000))
            call(
                "Emulation.setDeviceMetricsOverride",
                width=a.width,
                height=tall,
                deviceScaleFactor=1,
                mobile=False,
            )
            time.sleep(1.0)
            params["clip"] = {"x": 0, "y": 0, "width": a.width, "height": tall, "scale": 1}
        shot = call("Page.captureScreenshot", **params)
        with open(a.out, "wb") as f:
            f.write(base64.b64decode(shot["data"]))
        ws.close()
    finally:
        proc.terminate()
        try:
            proc.wait(10)
        except subprocess.TimeoutExpired:
            proc.kill()
        shutil.rmtree(profile, ignore_errors=True)
    print(a.out)


if __name__ == "__main__":
    main()
