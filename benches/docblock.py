#!/usr/bin/env python3
"""Rewrite a marked table of a document from a command's output, so that a re-measured figure
is pasted by a script and not typed by hand.

A block is `<!-- begin: table NAME -->`, its content, `<!-- end -->`. Usage:

    python3 benches/docblock.py FILE --list                 # the blocks of FILE
    python3 benches/docblock.py FILE NAME < table.md        # replace block NAME with stdin
    python3 benches/docblock.py FILE NAME --section HEADING < output.txt

With `--section`, only the part of the input under the Markdown heading HEADING (a line `## ...`
containing it, up to the next heading of that level) is used: the lab prints its tables that
way (`cargo run --release -p oit-lab -- peers | python3 benches/docblock.py docs/quality.md
budget --section 'Best method by memory budget'`).
"""
import re
import sys

BEGIN = re.compile(r"^<!-- begin: table (\S+) -->$")
END = "<!-- end -->"


def section(text, heading):
    out, level = [], None
    for line in text.splitlines():
        m = re.match(r"^(#+) ", line)
        if level is None:
            if m and heading in line:
                level = len(m.group(1))
            continue
        if m and len(m.group(1)) <= level:
            break
        out.append(line)
    if level is None:
        sys.exit(f"no heading containing {heading!r} in the input")
    return "\n".join(out).strip("\n")


def main():
    args = sys.argv[1:]
    if not args:
        sys.exit(__doc__)
    path = args[0]
    lines = open(path, encoding="utf-8").read().split("\n")
    if args[1:] == ["--list"]:
        for line in lines:
            m = BEGIN.match(line)
            if m:
                print(m.group(1))
        return
    name = args[1]
    content = sys.stdin.read().strip("\n")
    if "--section" in args:
        content = section(content, args[args.index("--section") + 1])
    out, i, done = [], 0, False
    while i < len(lines):
        out.append(lines[i])
        m = BEGIN.match(lines[i])
        if m and m.group(1) == name:
            j = i + 1
            while j < len(lines) and lines[j] != END:
                j += 1
            if j == len(lines):
                sys.exit(f"{path}: block {name} has no {END}")
            out.extend(content.split("\n"))
            i, done = j, True
            continue
        i += 1
    if not done:
        sys.exit(f"{path}: no block {name}")
    open(path, "w", encoding="utf-8").write("\n".join(out))


if __name__ == "__main__":
    main()
