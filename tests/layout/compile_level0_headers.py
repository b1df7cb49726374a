#!/usr/bin/env python3
"""Compiles every level-0 header alone (-fsyntax-only) with only the project's and Eigen's include
paths: a level-0 header that needs anything else, or that misses an include of its own, fails.
(Libraries installed straight under /usr/include, as Ceres and OctoMap are on Debian, stay
reachable; check_include_levels.py is the test that refuses them.)

  compile_level0_headers.py --compiler CXX --eigen DIR [--root DIR] [--jobs N]

The level-0 folders and the umbrella header come from check_include_levels.py's table. Exit 0: all
compile; 1: some fail (each printed with the compiler's first lines); 2: bad usage.
"""
import argparse
import concurrent.futures
import os
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from check_include_levels import FOLDERS, TOP_LEVEL_HEADERS  # noqa: E402


def level0_headers(root):
    base = os.path.join(root, "include", "cge")
    headers = [f"cge/{name}" for name, (rank, _) in sorted(TOP_LEVEL_HEADERS.items()) if rank < 1]
    for folder, (rank, _) in sorted(FOLDERS.items()):
        if rank >= 1 or not os.path.isdir(os.path.join(base, folder)):
            continue
        for directory, subdirs, files in os.walk(os.path.join(base, folder)):
            subdirs.sort()
            for file in sorted(files):
                if file.endswith(".hpp"):
                    headers.append(os.path.relpath(os.path.join(directory, file), os.path.join(root, "include")))
    return headers


def compile_one(compiler, root, eigen, header):
    # The header through a one-line translation unit, as a user includes it.
    command = [compiler, "-std=c++17", "-fsyntax-only", "-I", os.path.join(root, "include"), "-isystem", eigen, "-x", "c++", "-"]
    run = subprocess.run(command, input=f'#include "{header}"\n', capture_output=True, text=True)
    return header, run.returncode, run.stderr


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--compiler", required=True)
    parser.add_argument("--eigen", required=True, help="Eigen's include folder (holds Eigen/Core)")
    parser.add_argument("--root", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
    parser.add_argument("--jobs", type=int, default=2)
    args = parser.parse_args()
    if not os.path.exists(os.path.join(args.eigen, "Eigen", "Core")):
        print(f"compile_level0_headers: no Eigen/Core under --eigen {args.eigen}", file=sys.stderr)
        return 2
    headers = level0_headers(args.root)
    failed = 0
    with concurrent.futures.ThreadPoolExecutor(max_workers=max(1, args.jobs)) as pool:
        for header, rc, stderr in pool.map(lambda h: compile_one(args.compiler, args.root, args.eigen, h), headers):
            if rc != 0:
                failed += 1
                print(f"{header}: does not compile alone with only Eigen:")
                print("\n".join(stderr.splitlines()[:8]))
    if failed:
        return 1
    print(f"compile_level0_headers: {len(headers)} level-0 headers, each compiles alone with only Eigen")
    return 0


if __name__ == "__main__":
    sys.exit(main())
