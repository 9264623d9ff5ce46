#!/usr/bin/env python3
"""Checks on the project's text that a compiler cannot make.

  check_docs.py no-issue-citations ROOT
      Fails when a file of the source tree cites a tracker issue by number
      (the word issue or issues followed by a number, or a hash followed by
      a number): users cannot see the tracker, so docs, help texts and code
      comments say what and why instead.
  check_docs.py links ROOT
      Fails when a relative link in a markdown file of the tree points to a
      file that does not exist, or to a heading anchor (#...) that the target
      file does not have (GitHub's anchor rules).

ROOT is the source tree. The files are the ones git tracks there (a clean
clone, CI) or, without git, every file below ROOT outside build trees.
Each problem is printed as FILE:LINE: what, and the exit status is 1.
"""
import os
import re
import subprocess
import sys

# Built from parts so that this file does not match itself.
ISSUE_WORD = re.compile(r"\b[Ii]ssues?\s?#?" + r"[0-9]+")
HASH_NUMBER = re.compile(r"(?<![\w&#/])#" + r"[0-9]{1,4}\b")


def tracked_files(root):
    try:
        out = subprocess.run(["git", "-C", root, "ls-files", "-z"], check=True,
                             capture_output=True).stdout
        names = [n for n in out.decode().split("\0") if n]
        if names:
            return sorted(names)
    except (OSError, subprocess.CalledProcessError):
        pass
    names = []
    for dirpath, dirnames, filenames in os.walk(root):
        rel = os.path.relpath(dirpath, root)
        dirnames[:] = [d for d in dirnames if not d.startswith(".") and
                       not os.path.exists(os.path.join(dirpath, d, "CMakeCache.txt"))]
        for f in filenames:
            names.append(os.path.normpath(os.path.join(rel, f)))
    return sorted(names)


def read_text(path):
    try:
        with open(path, "rb") as f:
            data = f.read()
    except OSError:
        return None
    if b"\0" in data:
        return None
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError:
        return None


def no_issue_citations(root):
    problems = []
    me = os.path.realpath(__file__)
    for name in tracked_files(root):
        path = os.path.join(root, name)
        if os.path.realpath(path) == me:
            continue
        text = read_text(path)
        if text is None:
            continue
        for number, line in enumerate(text.splitlines(), 1):
            m = ISSUE_WORD.search(line) or HASH_NUMBER.search(line)
            if m:
                problems.append(f"{name}:{number}: cites an issue number ('{m.group(0)}'): "
                                f"say what and why instead: {line.strip()[:120]}")
    return problems


FENCE = re.compile(r"^\s*(```|~~~)")
HEADING = re.compile(r"^(#{1,6})\s+(.*?)\s*#*\s*$")
LINK = re.compile(r"(?<!!)\[(?:[^\[\]]|\[[^\]]*\])*\]\(\s*<?([^)\s>]+)>?(?:\s+\"[^\"]*\")?\s*\)")
IMAGE = re.compile(r"!\[[^\]]*\]\(\s*<?([^)\s>]+)>?(?:\s+\"[^\"]*\")?\s*\)")
INLINE_CODE = re.compile(r"(`+)(?:.*?)\1")
HTML_ANCHOR = re.compile(r"<a\s+(?:name|id)=\"([^\"]+)\"")


def prose_lines(text):
    """(line number, line) outside fenced code blocks, inline code removed."""
    fenced = False
    for number, line in enumerate(text.splitlines(), 1):
        if FENCE.match(line):
            fenced = not fenced
            continue
        if not fenced and not line.startswith("    "):
            yield number, INLINE_CODE.sub("", line)


def slug(heading):
    # GitHub: the heading's text (markup stripped), lower case, characters
    # other than letters, digits, '_', '-' and spaces removed, spaces -> '-'.
    text = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", heading)
    text = text.replace("`", "").replace("*", "")
    text = text.strip().lower()
    text = "".join(c for c in text if c.isalnum() or c in "_- ")
    return text.replace(" ", "-")


def anchors(text):
    found, seen = set(), {}
    fenced = False
    for line in text.splitlines():
        if FENCE.match(line):
            fenced = not fenced
            continue
        if fenced:
            continue
        m = HEADING.match(line)
        if m:
            s = slug(m.group(2))
            n = seen.get(s, 0)
            seen[s] = n + 1
            found.add(s if n == 0 else f"{s}-{n}")
        for a in HTML_ANCHOR.findall(line):
            found.add(a)
    return found


def links(root):
    problems = []
    cache = {}
    for name in tracked_files(root):
        if not name.endswith(".md"):
            continue
        text = read_text(os.path.join(root, name))
        if text is None:
            continue
        base = os.path.dirname(name)
        for number, line in prose_lines(text):
            for m in list(LINK.finditer(line)) + list(IMAGE.finditer(line)):
                target = m.group(1)
                if re.match(r"^[a-zA-Z][a-zA-Z0-9+.-]*:", target):
                    continue  # http:, https:, mailto: ...
                path, _, anchor = target.partition("#")
                file = os.path.normpath(os.path.join(base, path)) if path else name
                full = os.path.join(root, file)
                if not os.path.exists(full):
                    problems.append(f"{name}:{number}: link to '{target}': {file} does not exist")
                    continue
                if not anchor or not file.endswith(".md"):
                    continue
                if file not in cache:
                    cache[file] = anchors(read_text(full) or "")
                if anchor not in cache[file]:
                    problems.append(f"{name}:{number}: link to '{target}': {file} has no "
                                    f"heading with the anchor '#{anchor}'")
    return problems


def main():
    if len(sys.argv) != 3 or sys.argv[1] not in ("no-issue-citations", "links"):
        print(__doc__, file=sys.stderr)
        return 2
    root = sys.argv[2]
    problems = no_issue_citations(root) if sys.argv[1] == "no-issue-citations" else links(root)
    for p in problems:
        print(p)
    if problems:
        print(f"check_docs.py {sys.argv[1]}: {len(problems)} problem(s)", file=sys.stderr)
        return 1
    print(f"check_docs.py {sys.argv[1]}: ok")
    return 0


if __name__ == "__main__":
    sys.exit(main())
