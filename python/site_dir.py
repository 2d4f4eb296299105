#!/usr/bin/env python3
"""The site-packages folder under PREFIX for this interpreter (cmake --install of truss_deploy).
Usage: site_dir.py PREFIX; prints the folder.

The interpreter's own site folders under PREFIX come first (Debian: /usr/local ->
/usr/local/lib/python3.X/dist-packages, /usr -> /usr/lib/python3/dist-packages), so that an install
there is imported without PYTHONPATH, also from a venv made with --system-site-packages. Any other
prefix (a venv, /opt/truss) gets the standard PREFIX/lib/python3.X/site-packages, which is a venv's
own folder."""
import os
import site
import sys
import sysconfig


def site_dir(prefix):
    prefix = os.path.abspath(prefix)
    for p in site.getsitepackages():
        rel = os.path.relpath(os.path.abspath(p), prefix)
        if rel.split(os.sep)[0] in ("lib", "lib64"):  # directly under PREFIX/lib, not PREFIX/local/lib
            return os.path.abspath(p)
    return sysconfig.get_path("purelib", "posix_prefix", vars={"base": prefix, "platbase": prefix})


if __name__ == "__main__":
    print(site_dir(sys.argv[1]))
