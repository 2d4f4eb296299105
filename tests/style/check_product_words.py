#!/usr/bin/env python3
"""Fails on words about how the project was made, in what its users read.

The documentation, the report (postproc/), the READMEs, the Python package, the benchmarks a user
runs (bench/*.py), the tests a user reads to trust a number (tests/) and the strings of
the programs (string literals in src/ and python/*.cpp) speak of the product as it is: no issue
numbers, no history ("since ...", "earlier measurements"), no tools the project was built with
("reference search", "code corpus"). Each hit is printed as FILE:LINE: the word and why.

  check_product_words.py REPO_ROOT
Exit 0: none found; 1: hits (listed); 2: bad usage.
"""
import os
import re
import subprocess
import sys

# Written in pieces so that this file does not match its own patterns.
PATTERNS = [
    (r"\bissues?\s+#?\d+", "an issue number: the tracker is not part of the product"),
    (r"\bsince\s+(?:issue|commit|version\s+\d|the\s+(?:fix|rewrite|change))", "history: 'since' a change"),
    (r"\breference\s+" + "search", "a tool the project was made with"),
    (r"\bcode\s+" + "corpus", "a tool the project was made with"),
    (r"\bfound\s+by\s+the\s+project", "how the project was made"),
    (r"\bearlier\s+measurements?", "history: earlier figures belong to the version control"),
    (r"\bhistory\s+of\s+this\s+file", "history: the version control's, not the reader's"),
    (r"\bno\s+longer\s+exists?", "history: what used to be"),
    (r"\b(?:lands|landed)\s*;", "planning words"),
    (r"\bsplit\s+from\s+\w", "history: where code came from"),
]
PATTERNS = [(re.compile(p, re.IGNORECASE), why) for p, why in PATTERNS]

# Whole files (documentation, report, Python package) and string literals only (C++ sources).
WHOLE = (re.compile(r"^docs/.*\.md$"), re.compile(r"^postproc/.*\.(py|sh|toml|cfg)$"),
         re.compile(r"(^|/)README\.md$"), re.compile(r"^python/truss_deploy/.*\.py$"),
         re.compile(r"^scripts/run_main\.sh$"), re.compile(r"^bench/.*\.(py|sh)$"),
         re.compile(r"^tests/.*\.(py|sh|cpp|hpp|txt|cmake)$"))
SELF = "tests/style/check_product_words.py"  # names the words it looks for
STRINGS = (re.compile(r"^src/.*\.(cpp|hpp|h)$"), re.compile(r"^python/[^/]*\.(cpp|hpp)$"))
LITERAL = re.compile(r'"(?:[^"\\\n]|\\.)*"')


def tracked(root):
    out = subprocess.run(["git", "-C", root, "ls-files", "-z"], capture_output=True,
                         check=True).stdout
    return [f for f in out.decode().split("\0") if f]


def hits(text, strings_only):
    for n, line in enumerate(text.splitlines(), 1):
        parts = LITERAL.findall(line) if strings_only else [line]
        for part in parts:
            for rx, why in PATTERNS:
                m = rx.search(part)
                if m:
                    yield n, m.group(0), why


def main():
    if len(sys.argv) != 2:
        print(__doc__, file=sys.stderr)
        return 2
    root = os.path.abspath(sys.argv[1])
    bad = []
    for rel in tracked(root):
        whole = any(rx.search(rel) for rx in WHOLE)
        strings = any(rx.search(rel) for rx in STRINGS)
        if not (whole or strings) or rel == SELF:
            continue
        try:
            text = open(os.path.join(root, rel), encoding="utf-8").read()
        except (UnicodeDecodeError, FileNotFoundError, IsADirectoryError):
            continue
        bad += [f"{rel}:{n}: '{word}': {why}" for n, word, why in hits(text, not whole)]
    for b in bad:
        print(b)
    print(f"{len(bad)} word(s) about how the project was made" if bad else
          "no word about how the project was made in docs/, postproc/, READMEs, python/, bench/, "
          "tests/, the strings of src/")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
