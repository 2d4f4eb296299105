#!/usr/bin/env python3
"""Size limits of the C++ sources: no function in src/ over 120 lines; a source file over 500 lines
(generated tables, *.inc, aside) is listed as a prompt to ask whether it holds two concepts (files
are sized by concept: one concept is not cut in two to stay under a number), and one over
--hard-file (1000) lines fails; in the folders given to --narrow no line over
120 columns (so that no file gets under its limit by packing lines). Functions are found by brace
matching on the source with comments and string literals removed: a top-level or
namespace/class-level block opened by a line that looks like a definition (ends with ')'
[const/override/...] '{'). Python modules under --py-dir: at most 400 lines each. No folder of SRC_DIR above --max-folder-share of
the source lines (*.cpp, *.hpp; generated tables aside), so that the folders show the design.
Usage: check_sizes.py SRC_DIR [--max-function 120] [--max-file 500] [--hard-file 1000] [--max-folder-share 0.22] [--narrow FOLDER ...]
[--max-columns 120] [--py-dir postproc]; exit 1 on a violation."""
import argparse
import pathlib
import re
import sys


def strip(text):
    text = re.sub(r"/\*.*?\*/", lambda m: "\n" * m.group(0).count("\n"), text, flags=re.S)
    text = re.sub(r"//[^\n]*", "", text)
    text = re.sub(r'R"\((.*?)\)"', lambda m: '""' + "\n" * m.group(0).count("\n"), text, flags=re.S)
    text = re.sub(r'"(\\.|[^"\\\n])*"', '""', text)
    return re.sub(r"'(\\.|[^'\\\n])'", "''", text)


HEAD = re.compile(r"\)\s*(const|override|final|noexcept|mutable|->\s*[\w:<>,\s*&]+|\s)*\{\s*$")
SCOPE = re.compile(r"^\s*(namespace|class|struct|enum|union|extern)\b")


def functions(text):
    """Yields (name line, start line, length) of function bodies."""
    lines = strip(text).split("\n")
    depth, stack = 0, []  # stack of (depth at open, start line, is_function)
    for i, line in enumerate(lines, 1):
        for j, ch in enumerate(line):
            if ch == "{":
                head = line[: j + 1]
                k = i - 1
                while k > 0 and head.strip() in ("{",) and not lines[k - 1].strip().endswith(";"):
                    head = lines[k - 1] + head
                    k -= 1
                is_fn = bool(HEAD.search(head)) and not SCOPE.match(head) and not any(f for _, _, f in stack)
                stack.append((depth, i, is_fn))
                depth += 1
            elif ch == "}":
                depth -= 1
                if stack:
                    _, start, is_fn = stack.pop()
                    if is_fn:
                        yield lines[start - 1].strip()[:80], start, i - start + 1


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("src")
    ap.add_argument("--max-function", type=int, default=120)
    ap.add_argument("--max-file", type=int, default=500)
    ap.add_argument("--hard-file", type=int, default=1000)
    ap.add_argument("--narrow", nargs="*", default=[], help="folders of SRC_DIR whose lines are checked too")
    ap.add_argument("--max-columns", type=int, default=120)
    ap.add_argument("--py-dir", help="also check the Python modules under this folder")
    ap.add_argument("--max-py-file", type=int, default=400)
    ap.add_argument("--max-folder-share", type=float, default=0.22)
    a = ap.parse_args()
    bad = 0
    files = sorted(p for p in pathlib.Path(a.src).rglob("*") if p.suffix in (".cpp", ".hpp"))
    longest = (0, "")
    folder_lines = {}
    for p in files:
        text = p.read_text()
        n = text.count("\n")
        folder = p.relative_to(a.src).parts[0]
        folder_lines[folder] = folder_lines.get(folder, 0) + n
        if n > a.hard_file:
            print(f"{p}: {n} lines (limit {a.hard_file})")
            bad += 1
        elif n > a.max_file:
            print(f"{p}: {n} lines, over {a.max_file}: does it hold two concepts? (a prompt, not a failure)")
        if p.relative_to(a.src).parts[0] in a.narrow:
            for i, line in enumerate(text.split("\n"), 1):
                if len(line) > a.max_columns:
                    print(f"{p}:{i}: a line of {len(line)} columns (limit {a.max_columns})")
                    bad += 1
        for head, start, length in functions(text):
            if length > longest[0]:
                longest = (length, f"{p}:{start}")
            if length > a.max_function:
                print(f"{p}:{start}: function of {length} lines (limit {a.max_function}): {head}")
                bad += 1
    total = sum(folder_lines.values())
    for folder, n in sorted(folder_lines.items()):
        if n > a.max_folder_share * total:
            print(f"{a.src}/{folder}: {n} of {total} source lines ({n / total:.0%}, limit {a.max_folder_share:.0%})")
            bad += 1
    if a.py_dir:
        for p in sorted(pathlib.Path(a.py_dir).rglob("*.py")):
            n = p.read_text().count("\n")
            if n > a.max_py_file:
                print(f"{p}: {n} lines (limit {a.max_py_file})")
                bad += 1
    print(f"{len(files)} files checked; longest function {longest[0]} lines at {longest[1]}; {bad} over the limits")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
