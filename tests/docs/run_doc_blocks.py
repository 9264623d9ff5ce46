#!/usr/bin/env python3
"""Runs every shell block (```sh / ```bash) of the given Markdown files exactly
as printed, from the source tree's root, and fails on the first block that
exits non-zero.

A block that cannot run here (hardware, root, the network, ctest itself, a
recording from a robot) is marked on the line right before its fence:

    <!-- not run by ctest: REASON -->

The reason must be given; an unmarked block always runs. The source tree's
build directory must be `build/` (what the docs' commands name), else the
test is skipped (exit 77). Programs are also put on PATH (build/bin first),
as an installed tree would have them. Background jobs a block starts get
SIGINT when the block ends. LCM_DEFAULT_URL is set by the test (its own
port, ttl=0).

Usage: run_doc_blocks.py SOURCE_DIR BINARY_DIR DOC.md...
"""
import os
import re
import subprocess
import sys

MARK = re.compile(r"<!--\s*not run by ctest:\s*(.*?)\s*-->")
FENCE = re.compile(r"^(\s*)```(\w*)\s*$")


def blocks(path):
    """(line, lang, text, skip_reason or None) for each fenced block."""
    lines = open(path, encoding="utf-8").read().split("\n")
    out = []
    i = 0
    while i < len(lines):
        m = FENCE.match(lines[i])
        if not m:
            i += 1
            continue
        indent, lang, start = m.group(1), m.group(2), i
        body = []
        i += 1
        while i < len(lines) and not re.match(r"^\s*```\s*$", lines[i]):
            body.append(lines[i][len(indent):] if lines[i].startswith(indent) else lines[i])
            i += 1
        i += 1
        prev = lines[start - 1] if start > 0 else ""
        mark = MARK.search(prev)
        reason = None
        if mark:
            reason = mark.group(1)
            if not reason:
                sys.exit(f"{path}:{start}: 'not run by ctest' without a reason")
        out.append((start + 1, lang, "\n".join(body), reason))
    return out


def main():
    src, binary, docs = sys.argv[1], sys.argv[2], sys.argv[3:]
    if os.path.realpath(binary) != os.path.realpath(os.path.join(src, "build")):
        print(f"skipped: the build directory is {binary}, the docs' commands name build/")
        return 77
    env = dict(os.environ)
    env["PATH"] = os.path.join(src, "build", "bin") + os.pathsep + env.get("PATH", "")
    ran = skipped = 0
    for doc in docs:
        for line, lang, text, reason in blocks(os.path.join(src, doc)):
            if lang not in ("sh", "bash"):
                continue
            where = f"{doc}:{line}"
            if reason is not None:
                print(f"skip {where}: {reason}")
                skipped += 1
                continue
            print(f"run  {where}:\n" + "\n".join("     | " + t for t in text.splitlines()),
                  flush=True)
            script = ("trap 'for p in $(jobs -p); do kill -INT $p 2>/dev/null; done; wait' EXIT\n"
                      "set -e\n" + text + "\n")
            try:
                rc = subprocess.run(["bash", "-c", script], cwd=src, env=env,
                                    timeout=600).returncode
            except subprocess.TimeoutExpired:
                print(f"FAIL {where}: still running after 600 s")
                return 1
            if rc != 0:
                print(f"FAIL {where}: exit {rc}")
                return 1
            ran += 1
    print(f"{ran} passed, 0 failed, {skipped} skipped")
    return 0 if ran > 0 else 1


if __name__ == "__main__":
    sys.exit(main())
