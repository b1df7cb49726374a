"""The --expect mode shared by the repository's tree checkers (tests/docs/check_doc_citations.py,
tests/layout/check_include_levels.py): a run passes only when the problems it found are exactly the
lines of a file, which is how each checker's fixture test proves that it reports what it should and
nothing else."""
import sys


def compare_with_expected(tool, expect_path, problems):
    """Returns (exit status, number of expected problems): 0 when `problems` are exactly the
    lines of expect_path (blank lines and lines starting with # skipped), 1 when they differ (each
    difference printed), 2 when the file cannot be read (the reason on stderr, prefixed by tool)."""
    try:
        with open(expect_path, encoding="utf-8") as f:
            expected = [l.rstrip("\n") for l in f if l.strip() and not l.startswith("#")]
    except OSError as e:
        print(f"{tool}: cannot read --expect {expect_path}: {e.strerror}", file=sys.stderr)
        return 2, 0
    missing = [p for p in expected if p not in problems]
    extra = [p for p in problems if p not in expected]
    for p in missing:
        print(f"expected but not reported: {p}")
    for p in extra:
        print(f"reported but not expected: {p}")
    return (1 if missing or extra else 0), len(expected)
