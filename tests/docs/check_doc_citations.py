#!/usr/bin/env python3
"""Fails when a comment or a doc cites a Markdown file that is not in the repository.

Scans include/ src/ examples/ tests/ bench/ docs/ and README.md for names ending in ".md" and
checks, for each, that the file exists, and that a numbered section it names ("METHOD.md
section 4", "sections 4 and 5", "section 7.5" -> 7) has a heading "## 4." in that file. The one
document outside the repository that may be named is the input specification the method was
written from, and only in Markdown prose and only by its path beside the checkout
(../shared/docs/...): comments cite docs/METHOD.md instead.

  check_doc_citations.py [--root DIR] [--expect FILE]

--root: the tree to scan (default: the repository holding this script).
--expect: a list of the problems the tree must have, one "file:line: text" per line; the run
passes only when the problems found are exactly those (this is how the checker's own test proves
that it fails on bad citations and passes good ones).
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

SCANNED_DIRS = ("include", "src", "examples", "tests", "bench", "docs")
SCANNED_FILES = ("README.md",)
# Not scanned: generated files (their generator, examples/results/results_report.py, is scanned),
# fuzz inputs (bytes, not prose) and this checker's fixtures (bad citations on purpose).
SKIPPED = ("docs/RESULTS.md", "docs/results", "tests/fuzz/corpus", "tests/docs/fixtures")
# Documents beside the checkout (../shared/docs) that Markdown prose may name by that path.
SHARED_DOCS = ("ALGORITHMS", "PAPER_TABLES", "DESIGN")  # + ".md"
SHARED_PREFIX = "../shared/docs/"

MD = r"\.md"  # kept apart so that this file's own patterns are not citations
CITATION = re.compile(r"(?<![\w./-])((?:\.\./|\./)*[\w][\w./-]*" + MD + r")(?![\w])")
# "section 4", "sections 4 and 5", "sections 4-5", "section 7.5", also across a comment line
# break ("docs/METHOD" ".md\n// section 7.5").
SECTIONS = re.compile(r"[ \t]*(?:\n[ \t]*(?://+<?|#+|\*)?[ \t]*)?sections?[ \t]+"
                      r"(\d+(?:\.\d+)*(?:[ \t]*(?:,|and|-|to|or)[ \t]*\d+(?:\.\d+)*)*)")


def is_text(path):
    with open(path, "rb") as f:
        data = f.read()
    if b"\0" in data:
        return None
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError:
        return None


def files_to_scan(root):
    for name in SCANNED_FILES:
        if os.path.isfile(os.path.join(root, name)):
            yield name
    for top in SCANNED_DIRS:
        for dirpath, dirnames, filenames in os.walk(os.path.join(root, top)):
            rel_dir = os.path.relpath(dirpath, root).replace(os.sep, "/")
            dirnames[:] = sorted(d for d in dirnames if f"{rel_dir}/{d}" not in SKIPPED)
            for name in sorted(filenames):
                rel = f"{rel_dir}/{name}"
                if rel not in SKIPPED:
                    yield rel


def headings(path, cache):
    if path not in cache:
        with open(path, encoding="utf-8") as f:
            cache[path] = {int(m.group(1)) for m in re.finditer(r"(?m)^## (\d+)\.", f.read())}
    return cache[path]


def resolve(root, citing, cited):
    """The repository file a citation names, or None. Tried: the path from the root, from the
    citing file's folder, and (for a bare name) in docs/."""
    candidates = [os.path.join(root, cited), os.path.join(root, os.path.dirname(citing), cited)]
    if "/" not in cited:
        candidates.append(os.path.join(root, "docs", cited))
    real_root = os.path.realpath(root)
    for c in candidates:
        real = os.path.realpath(c)
        if os.path.isfile(real) and (real == real_root or real.startswith(real_root + os.sep)):
            return real
    return None


def check(root):
    problems = []
    count = 0
    cache = {}
    for rel in files_to_scan(root):
        text = is_text(os.path.join(root, rel))
        if text is None:
            continue
        is_prose = rel.endswith(MD.replace("\\", ""))
        for m in CITATION.finditer(text):
            cited = m.group(1)
            line = text.count("\n", 0, m.start()) + 1
            where = f"{rel}:{line}: "
            count += 1
            base = os.path.basename(cited)
            if base[:-3] in SHARED_DOCS:
                if not (is_prose and cited == SHARED_PREFIX + base):
                    problems.append(where + f"cites {cited}, which is not in the repository (only Markdown prose may "
                                    f"name it, as {SHARED_PREFIX}{base}); cite docs/METHOD.md section N instead")
                continue
            target = resolve(root, rel, cited)
            if target is None:
                problems.append(where + f"cites {cited}, which is not in the repository")
                continue
            s = SECTIONS.match(text, m.end())
            if s:
                have = headings(target, cache)
                for number in re.findall(r"\d+(?:\.\d+)*", s.group(1)):
                    top = int(number.split(".")[0])
                    if top not in have:
                        problems.append(where + f"cites {cited} section {number}, but {cited} has no heading "
                                        f"'## {top}.'")
    return problems, count


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--root", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
    parser.add_argument("--expect")
    args = parser.parse_args()
    if not os.path.isdir(args.root):
        print(f"check_doc_citations: --root {args.root} is not a folder", file=sys.stderr)
        return 2
    problems, count = check(args.root)
    if count == 0:
        print(f"check_doc_citations: no citation found under {args.root}: wrong root?", file=sys.stderr)
        return 1
    if args.expect is not None:
        status, expected = compare_with_expected("check_doc_citations", args.expect, problems)
        if status == 0:
            print(f"check_doc_citations: {count} citations, the {expected} expected problems and no other")
        return status
    for p in problems:
        print(p)
    if problems:
        print(f"check_doc_citations: {len(problems)} of {count} citations name no file or section of the repository")
        return 1
    print(f"check_doc_citations: {count} citations, all resolve")
    return 0


if __name__ == "__main__":
    sys.exit(main())
