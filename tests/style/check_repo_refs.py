#!/usr/bin/env python3
"""Fails on any reference to a path outside the repository.

A user's clone is the whole project: a source file, test, script or doc that points at
the lab's shared folder (`..` + `/shared/`), at the specification's old name (`MODEL` + `.md`), or at any `../` path that leaves the
repository sends its reader to a file they do not have. Checked over every file git tracks.

  check_repo_refs.py REPO_ROOT
"""
import os
import re
import subprocess
import sys

PATTERNS = [
    # The names are written in two pieces so that this file does not match its own patterns.
    (re.compile(r"\.\./" + "shared" + r"\b"), "points at the lab's shared folder, which a clone does not have"),
    (re.compile(r"(?<![\w/])" + "MODEL" + r"\.md"), "cites the specification's old name, which a clone does not have "
     "(docs/model.md is the model)"),
]
# a relative path inside a markdown link or a backquoted path: resolved against the file's folder
LINK = re.compile(r"\]\(((?:\.\./)+[^)#\s]*)")


def tracked(root):
    out = subprocess.run(["git", "-C", root, "ls-files", "-z"], capture_output=True, check=True).stdout
    return [f for f in out.decode().split("\0") if f]


def main():
    root = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else ".")
    me = os.path.relpath(os.path.abspath(__file__), root)
    bad = []
    for rel in tracked(root):
        if rel == me:
            continue
        path = os.path.join(root, rel)
        try:
            text = open(path, encoding="utf-8").read()
        except (UnicodeDecodeError, FileNotFoundError, IsADirectoryError):
            continue
        for n, line in enumerate(text.splitlines(), 1):
            for pat, why in PATTERNS:
                if pat.search(line):
                    bad.append(f"{rel}:{n}: {why}")
            for m in LINK.finditer(line):
                target = os.path.normpath(os.path.join(os.path.dirname(path), m.group(1)))
                if not target.startswith(root + os.sep):
                    bad.append(f"{rel}:{n}: link {m.group(1)} leaves the repository")
    for b in bad:
        print(b)
    print(f"{len(bad)} reference(s) outside the repository")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
