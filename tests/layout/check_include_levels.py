#!/usr/bin/env python3
"""Fails when a public header includes a library or a cge folder above its dependency level.

The levels (docs/ARCHITECTURE.md has the same table, README.md's layout section a summary):

  level 0  std + Eigen only, header-only (cge::core)
           0.0 core                                  (core/ includes nothing else of cge)
           0.1 graph, frontend, metrics, bow, voxels (may include 0.0)
           0.2 entropy, io                           (may include 0.0 and 0.1)
  level 1  one heavy dependency each, header-only, may include level 0
           opencv (OpenCV), ceres (Ceres), octomap (OctoMap)
  level 2  the compiled pipeline (cge::pipeline): OpenCV, Ceres and OctoMap, may include levels 0-1
           2.0 segmentation
           2.1 dataset, sim                          (may include 2.0)
           2.2 slam                                  (may include 2.0 and 2.1)
           2.3 mapping                               (may include 2.0 to 2.2)
           2.4 run                                   (may include 2.0 to 2.3)

A header in folder F may include a cge header of its own folder or of a folder of a lower rank
(level 1 folders do not include each other); a library header only if F's level allows it:
level 0 the C++ standard library (a bare name such as <vector>), Eigen and the few system
headers in SYSTEM_HEADERS; level 1 that and its own library; level 2 all three libraries. Every
folder under include/cge/ must be in FOLDERS (a new folder needs its level). The top-level headers
(include/cge/*.hpp) are checked under the names in TOP_LEVEL_HEADERS. The install's folder lists in
the top-level CMakeLists.txt (CGE_LEVEL0_FOLDERS, CGE_PIPELINE_FOLDERS) must name the same folders.

  check_include_levels.py [--root DIR] [--expect FILE]

--root: the tree whose include/cge/ is checked (default: the repository holding this script).
--expect: a list of the problems the tree must have, one "file:line: text" per line; the run
passes only when the problems found are exactly those (the checker's own test).
Exit 0: no problem (or exactly the expected ones); 1: problems, each printed as file:line: text;
2: bad usage.
"""
import argparse
import os
import re
import sys

sys.dont_write_bytecode = True  # no __pycache__ in the source tree
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "support"))
from expected_problems import compare_with_expected  # noqa: E402

# folder -> (rank, library group). Ranks order the folders; a folder includes only lower ranks
# (and itself). Level-1 folders share rank 1 and may not include one another.
FOLDERS = {
    "core": (0.0, "std"),
    "graph": (0.1, "std"), "frontend": (0.1, "std"), "metrics": (0.1, "std"), "bow": (0.1, "std"),
    "voxels": (0.1, "std"),
    "entropy": (0.2, "std"), "io": (0.2, "std"),
    "opencv": (1.0, "opencv"), "ceres": (1.0, "ceres"), "octomap": (1.0, "octomap"),
    "segmentation": (2.0, "pipeline"),
    "dataset": (2.1, "pipeline"), "sim": (2.1, "pipeline"),
    "slam": (2.2, "pipeline"),
    "mapping": (2.3, "pipeline"),
    "run": (2.4, "pipeline"),
}
# include/cge/<name>.hpp umbrella headers: cge.hpp gathers level 0 (above all of it); opencv.hpp and
# ceres.hpp gather their folder's headers and follow its rules.
TOP_LEVEL_HEADERS = {"cge.hpp": (0.3, "std"), "opencv.hpp": FOLDERS["opencv"], "ceres.hpp": FOLDERS["ceres"]}
# Library include prefixes of the heavy dependencies.
LIBRARIES = {"opencv": ("opencv2/",), "ceres": ("ceres/", "glog/"), "octomap": ("octomap/",)}
LIBRARY_NAMES = {"opencv": "OpenCV", "ceres": "Ceres", "octomap": "OctoMap"}
EIGEN = ("Eigen/", "unsupported/Eigen/")
# System headers level 0 may use besides the C++ standard library (POSIX, x86 intrinsics).
SYSTEM_HEADERS = ("unistd.h", "immintrin.h")

INCLUDE = re.compile(r'^\s*#\s*include\s*([<"])([^">]+)[">]')


def level_name(rank):
    return f"level {rank:g}"


def allowed_library(group, header):
    """Whether a header of library group `group` may include the <library> header `header`."""
    if "/" not in header and "." not in header:
        return True  # the C++ standard library
    if header.startswith(EIGEN) or header in SYSTEM_HEADERS:
        return True
    if group == "std":
        return False
    if group == "pipeline":
        return any(header.startswith(p) for prefixes in LIBRARIES.values() for p in prefixes)
    return header.startswith(LIBRARIES[group])


def check_header(root, relative, folder, rank, group, problems):
    """Checks one header of `folder` (None for a top-level header) with the rules of (rank, group)."""
    label = f"{folder}/" if folder else relative.split("/")[-1]
    # A folder's umbrella header (include/cge/opencv.hpp) includes that folder's headers.
    own = {label, label[:-len(".hpp")] + "/"} if folder is None else {label}
    path = os.path.join(root, relative)
    with open(path, encoding="utf-8", errors="replace") as f:
        lines = f.readlines()
    for number, line in enumerate(lines, start=1):
        m = INCLUDE.match(line)
        if not m:
            continue
        header = m.group(2).strip()
        where = f"{relative}:{number}"
        if header.startswith("cge/"):
            parts = header.split("/")
            if len(parts) > 2 and parts[1] in FOLDERS:
                target, target_rank = f"{parts[1]}/", FOLDERS[parts[1]][0]
            elif len(parts) == 2 and parts[1] in TOP_LEVEL_HEADERS:
                target, target_rank = parts[1], TOP_LEVEL_HEADERS[parts[1]][0]
            else:
                problems.append(f"{where}: includes {header}, which is in no level of check_include_levels.py")
                continue
            if target in own:
                continue
            if target_rank >= rank:
                problems.append(f"{where}: {label} ({level_name(rank)}) includes {header} of {target} "
                                f"({level_name(target_rank)}), which is not below it")
        elif m.group(1) == '"':
            problems.append(f"{where}: includes \"{header}\": public headers include cge headers as "
                            f"\"cge/<folder>/<name>.hpp\"")
        elif not allowed_library(group, header):
            if group == "std":
                allowed = "the standard library and Eigen"
            elif group == "pipeline":
                allowed = "the standard library, Eigen, OpenCV, Ceres and OctoMap"
            else:
                allowed = f"the standard library, Eigen and {LIBRARY_NAMES[group]}"
            problems.append(f"{where}: {label} ({level_name(rank)}) includes <{header}>; it may use only "
                            f"{allowed}")


CMAKE_LISTS = {"CGE_LEVEL0_FOLDERS": "std", "CGE_PIPELINE_FOLDERS": "pipeline"}


def check_install_lists(root, problems):
    """The folder lists of the top-level CMakeLists.txt (what `cmake --install` copies per level)
    name exactly the folders of FOLDERS with that level's library group."""
    path = os.path.join(root, "CMakeLists.txt")
    if not os.path.exists(path):
        return
    with open(path, encoding="utf-8") as f:
        text = f.read()
    for variable, group in CMAKE_LISTS.items():
        m = re.search(r"^\s*set\(\s*" + variable + r"\s+([^)]*)\)", text, re.MULTILINE)
        line = text[:m.start()].count("\n") + 1 if m else 0
        if m is None:
            problems.append(f"CMakeLists.txt: no set({variable} ...) (the install's folder list)")
            continue
        listed = set(m.group(1).split())
        table = {folder for folder, (_, g) in FOLDERS.items() if g == group}
        for folder in sorted(table - listed):
            problems.append(f"CMakeLists.txt:{line}: {variable} lacks {folder}/, which its level holds")
        for folder in sorted(listed - table):
            problems.append(f"CMakeLists.txt:{line}: {variable} lists {folder}/, which is not of its level")


def check_tree(root):
    problems = []
    check_install_lists(root, problems)
    base = os.path.join(root, "include", "cge")
    if not os.path.isdir(base):
        raise FileNotFoundError(f"no folder {base}")
    headers = 0
    for name in sorted(os.listdir(base)):
        path = os.path.join(base, name)
        if os.path.isdir(path):
            if name not in FOLDERS:
                problems.append(f"include/cge/{name}: folder in no level (add it to FOLDERS in "
                                f"tests/layout/check_include_levels.py and to docs/ARCHITECTURE.md)")
                continue
            for directory, subdirs, files in os.walk(path):
                subdirs.sort()
                for file in sorted(files):
                    if file.endswith((".hpp", ".h")):
                        relative = os.path.relpath(os.path.join(directory, file), root).replace(os.sep, "/")
                        check_header(root, relative, name, *FOLDERS[name], problems)
                        headers += 1
        elif name.endswith((".hpp", ".h")):
            if name not in TOP_LEVEL_HEADERS:
                problems.append(f"include/cge/{name}: top-level header in no level (add it to TOP_LEVEL_HEADERS)")
                continue
            check_header(root, f"include/cge/{name}", None, *TOP_LEVEL_HEADERS[name], problems)
            headers += 1
    return problems, headers


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--root", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
    parser.add_argument("--expect")
    args = parser.parse_args()
    try:
        problems, headers = check_tree(args.root)
    except OSError as e:
        print(f"check_include_levels: {e}", file=sys.stderr)
        return 2
    if args.expect is not None:
        status, expected = compare_with_expected("check_include_levels", args.expect, problems)
        if status == 0:
            print(f"check_include_levels: {headers} headers, the {expected} expected problems and no other")
        return status
    for p in problems:
        print(p)
    if problems:
        return 1
    print(f"check_include_levels: {headers} headers, every include within its level")
    return 0


if __name__ == "__main__":
    sys.exit(main())
