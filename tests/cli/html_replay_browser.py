#!/usr/bin/env python3
"""The HTML replay in a real browser (headless Chromium), end to end through the command line.

    html_replay_browser.py OCCTRACK_CLI CHROMIUM SCENARIO WORK_DIR

Runs `occtrack run SCENARIO --html` and opens the page twice: with #selftest (the page moves its slider over
the episode, checks each frame's drawing and catches script errors, and writes "ok ..." into <pre
id="selftest">, read back with --dump-dom), and for a screenshot at t = 10 s, whose PNG must show the
obstacles', the robot's and the scan's colours. Standard library only. Exits 77 (ctest: skipped) when
CHROMIUM is empty or missing.
"""
import os
import re
import struct
import subprocess
import sys
import tempfile
import time
import zlib

# io/html_replay's colours.
OBSTACLE = (0x9E, 0x9E, 0x9E)
ROBOT = (0x1F, 0x77, 0xB4)
SCAN = (0xFF, 0x7F, 0x0E)


def fail(message):
    print("FAIL: " + message)
    sys.exit(1)


def chromium(binary, url, *options):
    """Runs headless Chromium on `url` with a fresh profile and nothing that reaches the network."""
    with tempfile.TemporaryDirectory() as profile:
        command = [binary, "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                   "--disable-background-networking", "--disable-component-update", "--disable-sync",
                   "--user-data-dir=" + profile, *options, url]
        done = subprocess.run(command, capture_output=True, text=True, timeout=60)
    if done.returncode != 0:
        fail("chromium exited with %d: %s" % (done.returncode, done.stderr[-2000:]))
    return done.stdout


def read_png(path):
    """(width, height, rows of RGB(A) pixels) of an 8-bit, non-interlaced RGB or RGBA PNG."""
    with open(path, "rb") as f:
        data = f.read()
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        fail(path + ": not a PNG")
    at, idat = 8, b""
    while at < len(data):
        length, kind = struct.unpack(">I4s", data[at:at + 8])
        body = data[at + 8:at + 8 + length]
        if kind == b"IHDR":
            width, height, depth, colour, _, _, interlace = struct.unpack(">IIBBBBB", body)
            if depth != 8 or colour not in (2, 6) or interlace != 0:
                fail("%s: unsupported PNG (depth %d, colour type %d, interlace %d)" % (path, depth, colour, interlace))
            channels = 3 if colour == 2 else 4
        elif kind == b"IDAT":
            idat += body
        at += 12 + length
    raw, stride, rows, previous = zlib.decompress(idat), width * channels, [], bytearray(width * channels)
    for y in range(height):
        line = raw[y * (stride + 1):(y + 1) * (stride + 1)]
        kind, row = line[0], bytearray(line[1:])
        for i in range(stride):  # the five PNG filters
            a = row[i - channels] if i >= channels else 0
            b = previous[i]
            c = previous[i - channels] if i >= channels else 0
            if kind == 1:
                row[i] = (row[i] + a) & 255
            elif kind == 2:
                row[i] = (row[i] + b) & 255
            elif kind == 3:
                row[i] = (row[i] + (a + b) // 2) & 255
            elif kind == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                row[i] = (row[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        rows.append(row)
        previous = row
    return width, height, channels, rows


def count(png, colour, tolerance=3):
    width, _, channels, rows = png
    hits = 0
    for row in rows:
        for x in range(0, width * channels, channels):
            if all(abs(row[x + k] - colour[k]) <= tolerance for k in range(3)):
                hits += 1
    return hits


def main():
    if len(sys.argv) != 5:
        print(__doc__)
        return 2
    cli, browser, scenario, work = sys.argv[1:]
    if not browser or not os.path.exists(browser):
        print("SKIP: chromium not found (looked for /usr/bin/chromium); the HTML replay's browser test did not run")
        return 77
    os.makedirs(work, exist_ok=True)
    page = os.path.join(work, "replay.html")
    started = time.monotonic()
    # Proj-CEM for plans and candidates; a small batch keeps the run to seconds (still 10 candidates a cycle).
    run = subprocess.run([cli, "run", scenario, "--planner", "projcem", "--samples", "32", "--html", page],
                         capture_output=True, text=True, timeout=120)
    if run.returncode != 0:
        fail("occtrack run exited with %d: %s" % (run.returncode, run.stderr[-2000:]))
    print("occtrack run: %.1f s, page %d bytes" % (time.monotonic() - started, os.path.getsize(page)))
    url = "file://" + os.path.abspath(page)

    # (a) The page's self-test, read back from the DOM.
    started = time.monotonic()
    dom = chromium(browser, url + "#selftest", "--virtual-time-budget=5000", "--dump-dom")
    found = re.search(r'<pre id="selftest">(.*?)</pre>', dom, re.S)
    if not found:
        fail("no <pre id=\"selftest\"> in the DOM:\n" + dom[:2000])
    result = found.group(1).strip()
    print("self-test (%.1f s): %s" % (time.monotonic() - started, result))
    if not result.startswith("ok "):
        fail("the page's self-test: " + (result or "(empty: the script did not run)"))

    # (b) A screenshot at t = 10 s is not blank: obstacles, the robot and the scan are drawn.
    started = time.monotonic()
    shot = os.path.join(work, "replay.png")
    if os.path.exists(shot):
        os.remove(shot)
    chromium(browser, url + "#t=10", "--virtual-time-budget=5000", "--screenshot=" + shot, "--window-size=1200,900",
             "--hide-scrollbars")
    if not os.path.exists(shot):
        fail("chromium wrote no screenshot")
    png = read_png(shot)
    counts = {name: count(png, colour) for name, colour in (("obstacle", OBSTACLE), ("robot", ROBOT), ("scan", SCAN))}
    print("screenshot %s (%.1f s): %dx%d, pixels %s" % (shot, time.monotonic() - started, png[0], png[1], counts))
    blank = [name for name, hits in counts.items() if hits == 0]
    if blank:
        fail("the screenshot shows no " + ", ".join(blank))
    print("ok")
    return 0


if __name__ == "__main__":
    sys.exit(main())
