#!/usr/bin/env python3
"""scripts/results.sh --quick into a temporary folder: it must succeed, write RESULTS.md, and
every figure RESULTS.md shows or links must exist and be a PNG (or JPEG) that decodes: the PNG
signature, chunks with correct CRCs, an IHDR of a non-empty image, IDAT data that inflates to
the size the IHDR implies, and IEND. No table cell may be NaN.

  results_test.py SOURCE_DIR BUILD_DIR [DATA_DIR]
"""
import os
import re
import shutil
import struct
import subprocess
import sys
import tempfile
import zlib


def check_png(path):
    with open(path, "rb") as f:
        data = f.read()
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        return "no PNG signature"
    pos, idat, ihdr, end = 8, b"", None, False
    while pos + 8 <= len(data):
        length, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + length]
        crc = data[pos + 8 + length:pos + 12 + length]
        if len(body) != length or len(crc) != 4:
            return "truncated %s chunk" % kind
        if zlib.crc32(kind + body) & 0xFFFFFFFF != struct.unpack(">I", crc)[0]:
            return "bad CRC in %s chunk" % kind
        if kind == b"IHDR":
            ihdr = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            idat += body
        elif kind == b"IEND":
            end = True
            break
        pos += 12 + length
    if not ihdr or not end:
        return "no IHDR or no IEND"
    width, height, depth, colour = ihdr[:4]
    if width == 0 or height == 0:
        return "empty image"
    channels = {0: 1, 2: 3, 3: 1, 4: 2, 6: 4}[colour]
    expected = height * (1 + (width * channels * depth + 7) // 8)
    if len(zlib.decompress(idat)) != expected:
        return "image data does not match %dx%d" % (width, height)
    return None


def main():
    source, build = sys.argv[1], sys.argv[2]
    data = sys.argv[3] if len(sys.argv) > 3 else os.path.join(source, "..", "shared", "data")
    out = tempfile.mkdtemp(prefix="upd-results-test.")
    try:
        cmd = [os.path.join(source, "scripts", "results.sh"), "--quick", "--output", out,
               "--build", build, "--data", data]
        run = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        print(run.stdout)
        if run.returncode != 0:
            print("FAIL: results.sh exited with %d" % run.returncode)
            return 1
        if not os.path.isdir(data):
            print("note: shared data absent: the real-frame part was skipped (as the output says)")
        md = open(os.path.join(out, "RESULTS.md")).read()
        targets = re.findall(r"\]\(([^)#\s]+)\)", md)
        figures = [t for t in targets if not re.match(r"[a-z]+:", t) and t.endswith((".png", ".jpg"))]
        failures = []
        if len(figures) < 8:
            failures.append("only %d figures referenced" % len(figures))
        for t in figures:
            path = os.path.join(out, t)
            if not os.path.isfile(path):
                failures.append("%s: missing" % t)
            elif t.endswith(".png"):
                err = check_png(path)
                if err:
                    failures.append("%s: %s" % (t, err))
            elif open(path, "rb").read(3) != b"\xff\xd8\xff":
                failures.append("%s: not a JPEG" % t)
        for line in md.splitlines():
            if line.startswith("|") and re.search(r"\|\s*(nan|-?inf)\s*\|", line, re.I):
                failures.append("a table cell is not a number: " + line)
        for f in failures:
            print("FAIL:", f)
        print("%d figures checked" % len(figures))
        return 1 if failures else 0
    finally:
        shutil.rmtree(out, ignore_errors=True)


if __name__ == "__main__":
    sys.exit(main())
