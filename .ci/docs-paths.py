#!/usr/bin/env python3
"""Every repository path that README.md, docs/*.md and the crate docs (src/lib.rs) name exists.

A path is a `code span` or a Markdown link target that names a file or folder of the
repository: it starts with a top-level entry of the repository (`src/...`, `benches/...`,
`Cargo.toml`), or it is a bare file name with a source or document extension (`x8.rs`), which
some file of the repository must have. Generated outputs (`out/`, `target*/`), placeholders
(`<hash>`, `*`, `$VAR`), URLs and absolute paths are not checked; a path that leaves the
repository (`../`) fails. Prints each missing path with its file and line and exits 1 if any.

    python3 .ci/docs-paths.py
"""
import os
import re
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
EXTENSIONS = (".rs", ".md", ".sh", ".py", ".toml", ".c", ".h", ".wgsl", ".png", ".svg", ".mjs", ".json", ".txt", ".lock", ".yml")


def tracked():
    try:
        out = subprocess.run(["git", "ls-files", "-co", "--exclude-standard"], cwd=ROOT, capture_output=True, text=True, check=True).stdout
        files = out.split()
    except (OSError, subprocess.CalledProcessError):
        files = [os.path.relpath(os.path.join(d, f), ROOT) for d, _, fs in os.walk(ROOT) for f in fs]
    return set(files)


def sources():
    yield "README.md", open(os.path.join(ROOT, "README.md"), encoding="utf-8").read().splitlines()
    for name in sorted(os.listdir(os.path.join(ROOT, "docs"))):
        if name.endswith(".md"):
            path = os.path.join("docs", name)
            yield path, open(os.path.join(ROOT, path), encoding="utf-8").read().splitlines()
    lib = open(os.path.join(ROOT, "src", "lib.rs"), encoding="utf-8").read().splitlines()
    # Crate docs only (`//!`), and the doc comments of the crate root.
    yield "src/lib.rs", [l if l.lstrip().startswith(("//!", "///")) else "" for l in lib]


def candidates(line):
    for m in re.finditer(r"`([^`\s]+)`", line):
        yield m.group(1)
    for m in re.finditer(r"\]\(([^)\s]+)\)", line):
        yield m.group(1)


def main():
    files = tracked()
    dirs = {os.path.dirname(f) for f in files}
    while "" in dirs:
        dirs.discard("")
    for d in list(dirs):
        while d:
            dirs.add(d)
            d = os.path.dirname(d)
    top = {p.split("/")[0] for p in files}
    basenames = {os.path.basename(f) for f in files}
    missing = 0
    for doc, lines in sources():
        here = os.path.dirname(doc)
        for n, line in enumerate(lines, 1):
            for token in candidates(line):
                path = token.split("#")[0]
                path = re.sub(r":\d[\d,\-]*$", "", path)  # file.rs:120-140
                path = path.rstrip(".,;:)")
                if not path or "://" in token or path.startswith(("/", "~", "-")):
                    continue
                if any(c in path for c in "<>*$?{}[]|=\\\"'") or "::" in path:
                    continue
                if not re.fullmatch(r"[A-Za-z0-9_.\-/+]+", path):
                    continue
                if path.startswith("../") and os.path.normpath(os.path.join(here, path)).startswith(".."):
                    print(f"{doc}:{n}: {token}: outside the repository")
                    missing += 1
                    continue
                norm = os.path.normpath(path).rstrip("/")
                first = norm.split("/")[0]
                if "/" in norm or first in top:
                    if first == "out" or any(c == "target" or c.startswith("target-") for c in norm.split("/")):
                        continue
                    if first not in top:
                        # Relative to the document (`[frame.md](frame.md)` in docs/).
                        rel = os.path.normpath(os.path.join(here, norm))
                        if rel.split("/")[0] in top and (rel in files or rel in dirs):
                            continue
                        if first.endswith(EXTENSIONS) or "." in os.path.basename(norm):
                            pass  # a file path under an unknown folder: check below
                        else:
                            continue  # `x86-64-v3/v4`, `SSE2/AVX2`: not a path
                    if norm in files or norm in dirs:
                        continue
                    rel = os.path.normpath(os.path.join(here, norm))
                    if rel in files or rel in dirs:
                        continue
                    print(f"{doc}:{n}: {token}: no such file or folder")
                    missing += 1
                elif norm.endswith(EXTENSIONS) and re.fullmatch(r"[A-Za-z0-9_.\-]+", norm):
                    if norm not in basenames:
                        print(f"{doc}:{n}: {token}: no file of that name in the repository")
                        missing += 1
    if missing:
        print(f"{missing} path(s) named in the docs do not exist")
        return 1
    print("docs paths: every path named in README.md, docs/*.md and src/lib.rs exists")
    return 0


if __name__ == "__main__":
    sys.exit(main())
