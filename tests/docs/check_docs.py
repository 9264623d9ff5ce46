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

  check_docs.py commands ROOT BINDIR
      Fails when a command printed in a markdown file of the tree (a code
      span or a code block) names a program `build/bin/X` that BINDIR does
      not hold, a script `scripts/X` that does not exist, a subcommand
      (`tsm X`, `tsm-link X`, `tsm-devices X`) the program's --help does not
      list, or a `--flag` that the --help of the program (and subcommand)
      it is given to does not list. Only programs that answer --help with
      their usage are asked (a benchmark that would run instead is not).

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


def markdown_pages(root):
    """(name, text) of every tracked Markdown page that reads as text."""
    for name in tracked_files(root):
        if not name.endswith(".md"):
            continue
        text = read_text(os.path.join(root, name))
        if text is not None:
            yield name, text


def links(root):
    problems = []
    cache = {}
    for name, text in markdown_pages(root):
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


def code_texts(text):
    """(line number, code) for each code block line and each code span."""
    fenced = False
    pending, start = "", 0
    for number, line in enumerate(text.splitlines(), 1):
        if FENCE.match(line):
            fenced = not fenced
            continue
        if fenced or line.startswith("    "):
            # A shell line continued with a backslash is one command.
            if not pending:
                start = number
            if line.rstrip().endswith("\\"):
                pending += line.rstrip()[:-1] + " "
                continue
            yield start, pending + line
            pending = ""
            continue
        for m in re.finditer(r"(`+)(.+?)\1", line):
            yield number, m.group(2)


SEGMENT_SPLIT = re.compile(r"\|\||&&|[|;&()]|\$\(")
SUBCOMMAND_PROGRAMS = ("tsm", "tsm-link", "tsm-devices")


class Programs:
    """The programs of BINDIR and what their --help says, asked once each."""

    def __init__(self, bindir):
        self.bindir = bindir
        self.names = set(os.listdir(bindir)) if os.path.isdir(bindir) else set()
        self.helps = {}

    def answers_help(self, name):
        # Only a program whose binary knows the word --help prints its usage
        # for it; others (benchmarks, tools with their own argument loop)
        # would run instead.
        try:
            with open(os.path.join(self.bindir, name), "rb") as f:
                return b"--help" in f.read()
        except OSError:
            return False

    def help(self, name, sub=None):
        key = (name, sub)
        if key not in self.helps:
            text = None
            if self.answers_help(name):
                argv = [os.path.join(self.bindir, name)] + ([sub] if sub else []) + ["--help"]
                try:
                    r = subprocess.run(argv, capture_output=True, timeout=20,
                                       stdin=subprocess.DEVNULL)
                    text = (r.stdout + r.stderr).decode("utf-8", "replace")
                except (OSError, subprocess.TimeoutExpired):
                    text = None
            self.helps[key] = text
        return self.helps[key]

    def subcommands(self, name):
        text = self.help(name) or ""
        m = re.search(r"^Subcommands:\n((?:  .*\n?)*)", text, re.M)
        if not m:
            return set()
        return {line.split()[0] for line in m.group(1).splitlines() if line.strip()}


def has_flag(help_text, flag):
    return re.search(r"(?<![\w-])" + re.escape(flag) + r"(?![\w-])", help_text) is not None


def commands(root, bindir):
    programs = Programs(bindir)
    if not programs.names:
        return [f"{bindir}: no programs there (build first)"]
    problems = []
    for name, text in markdown_pages(root):
        for number, code in code_texts(text):
            for segment in SEGMENT_SPLIT.split(code):
                words = segment.split()
                while words and (re.match(r"^[A-Za-z_][A-Za-z0-9_]*=", words[0]) or
                                 words[0] in ("sudo", "exec", "time", "then", "do", "!")):
                    words = words[1:]
                if not words:
                    continue
                word = words[0].strip("[]")
                where = f"{name}:{number}"
                if word.startswith(("scripts/", "./scripts/")):
                    script = word[2:] if word.startswith("./") else word
                    if "*" not in script and not os.path.exists(os.path.join(root, script)):
                        problems.append(f"{where}: '{word}': {script} does not exist")
                    continue
                if word.startswith(("build/bin/", "./build/bin/")):
                    program = word.split("build/bin/", 1)[1]
                    if not program or "*" in program or "<" in program or program.endswith("_"):
                        continue  # a family: build/bin/bench_*
                    if program not in programs.names:
                        problems.append(f"{where}: '{word}': {bindir} has no program '{program}'")
                        continue
                elif word in programs.names:
                    program = word
                else:
                    continue
                sub = None
                rest = words[1:]
                if program in SUBCOMMAND_PROGRAMS and rest and re.match(r"^[a-z][a-z-]*$", rest[0]):
                    subs = programs.subcommands(program)
                    if subs and rest[0] not in subs:
                        problems.append(f"{where}: '{program} {rest[0]}': not a subcommand of "
                                        f"{program} (it has: {', '.join(sorted(subs))})")
                        continue
                    sub = rest[0]
                help_text = programs.help(program)
                if help_text is None:
                    continue
                if sub:
                    help_text += programs.help(program, sub) or ""
                else:
                    # `tsm ... --flag`: an option of any of its subcommands.
                    for other in sorted(programs.subcommands(program)):
                        help_text += programs.help(program, other) or ""
                for token in rest:
                    flag = re.match(r"^[\[{(\"']*(--[A-Za-z][A-Za-z0-9_-]*)", token)
                    if flag and not has_flag(help_text, flag.group(1)):
                        shown = f"{program} {sub}" if sub else program
                        problems.append(f"{where}: '{shown} {flag.group(1)}': not an option "
                                        f"of {shown} (its --help does not list it)")
    return problems


def main():
    modes = {"no-issue-citations": 3, "links": 3, "commands": 4}
    if len(sys.argv) < 2 or modes.get(sys.argv[1]) != len(sys.argv):
        print(__doc__, file=sys.stderr)
        return 2
    root = sys.argv[2]
    if sys.argv[1] == "commands":
        problems = commands(root, sys.argv[3])
    elif sys.argv[1] == "no-issue-citations":
        problems = no_issue_citations(root)
    else:
        problems = links(root)
    for p in problems:
        print(p)
    if problems:
        print(f"check_docs.py {sys.argv[1]}: {len(problems)} problem(s)", file=sys.stderr)
        return 1
    print(f"check_docs.py {sys.argv[1]}: ok")
    return 0


if __name__ == "__main__":
    sys.exit(main())
