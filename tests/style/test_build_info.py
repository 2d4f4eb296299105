#!/usr/bin/env python3
"""cmake/build_info.cmake on a scratch git repository, against git's own answers: the generated
source names the commit `git rev-parse --short HEAD` gives, "-dirty" while a tracked file differs
from it, the new commit after a commit, "unknown" outside git; and it is left untouched (same
mtime) when nothing changed, so a build with an unchanged revision recompiles nothing.
Usage: test_build_info.py --script cmake/build_info.cmake --scratch DIR; exit 1 on a failure."""
import argparse
import os
import re
import shutil
import subprocess
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "postproc"))
from checks import FAILS, check  # noqa: E402


def git(repo, *args):
    env = dict(os.environ, GIT_AUTHOR_NAME="t", GIT_AUTHOR_EMAIL="t@t", GIT_COMMITTER_NAME="t",
               GIT_COMMITTER_EMAIL="t@t")
    return subprocess.run(["git", *args], cwd=repo, check=True, capture_output=True, text=True, env=env).stdout.strip()


def generate(script, source_dir, out):
    # The ceiling keeps git from finding a repository above the scratch directory (a build tree
    # inside a clone), so "outside git" is outside git.
    env = dict(os.environ, GIT_CEILING_DIRECTORIES=os.path.dirname(out))
    subprocess.run(["cmake", f"-DSOURCE_DIR={source_dir}", "-DVERSION=9.8.7", f"-DOUT={out}", "-P", script],
                   check=True, capture_output=True, env=env)
    with open(out, encoding="utf-8") as fh:
        text = fh.read()
    rev = re.search(r'get_git_revision\(\) \{ return "([^"]*)"; \}', text)
    ver = re.search(r'get_software_version\(\) \{ return "([^"]*)"; \}', text)
    return (rev.group(1) if rev else None), (ver.group(1) if ver else None)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--script", required=True)
    ap.add_argument("--scratch", required=True)
    a = ap.parse_args()
    script, scratch = os.path.abspath(a.script), os.path.abspath(a.scratch)
    shutil.rmtree(scratch, ignore_errors=True)
    repo, out = os.path.join(scratch, "repo"), os.path.join(scratch, "build_info.cpp")
    os.makedirs(repo)
    git(repo, "init", "-q")
    with open(os.path.join(repo, "a.txt"), "w") as fh:
        fh.write("one\n")
    git(repo, "add", "a.txt")
    git(repo, "commit", "-q", "-m", "first")

    rev, ver = generate(script, repo, out)
    first = git(repo, "rev-parse", "--short", "HEAD")
    check(rev == first and ver == "9.8.7", f"a clean checkout: {rev!r} is git's {first!r}, version {ver!r}")
    os.utime(out, (1_000_000_000, 1_000_000_000))
    generate(script, repo, out)
    check(os.stat(out).st_mtime == 1_000_000_000, "nothing changed: the source is not rewritten (no recompile)")

    with open(os.path.join(repo, "a.txt"), "a") as fh:
        fh.write("two\n")
    rev, _ = generate(script, repo, out)
    check(rev == first + "-dirty", f"a tracked file changed: {rev!r} is {first + '-dirty'!r}")
    check(os.stat(out).st_mtime != 1_000_000_000, "the changed revision rewrites the source")

    git(repo, "commit", "-q", "-am", "second")
    rev, _ = generate(script, repo, out)
    second = git(repo, "rev-parse", "--short", "HEAD")
    check(rev == second and second != first, f"after a commit: {rev!r} is git's new {second!r}")

    bare = os.path.join(scratch, "not_git")
    os.makedirs(bare)
    rev, _ = generate(script, bare, out)
    check(rev == "unknown", f"outside git: {rev!r}")

    print(f"{len(FAILS)} check(s) failed" if FAILS else "all checks passed")
    return 1 if FAILS else 0


if __name__ == "__main__":
    sys.exit(main())
