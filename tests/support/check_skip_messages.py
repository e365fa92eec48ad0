#!/usr/bin/env python3
"""A long numerical test skips itself under a sanitizer or qemu (RSD_SKIP_LONG_IN_SLOW_BUILD in
tests/support/sanitizer.hpp), naming the tests that run the same code there. Each name must be a
test that exists and does not skip itself too: else the skip message promises coverage that no
test gives. `Suite.*` needs one test of the suite that runs.

    check_skip_messages.py TESTS_DIR     (exit 0: every name holds; 1: each broken one said)
"""
import pathlib
import re
import sys

HEADER = re.compile(r"^TEST(?:_F|_P)?\(\s*(\w+)\s*,\s*(\w+)\s*\)", re.M)
SKIP = re.compile(r'RSD_SKIP_LONG_IN_SLOW_BUILD\(\s*((?:"(?:[^"\\]|\\.)*"\s*)+)\)')
NAME = re.compile(r"\b([A-Z]\w*)\.(\*|[A-Z]\w*)")


def tests_in(path):
    """(name, body) for every test of a file: a body runs to the next test's header."""
    text = path.read_text(encoding="utf-8")
    heads = list(HEADER.finditer(text))
    for i, h in enumerate(heads):
        end = heads[i + 1].start() if i + 1 < len(heads) else len(text)
        yield f"{h.group(1)}.{h.group(2)}", text[h.end():end]


def main(root):
    every, skipping, claims = set(), set(), []
    for path in sorted(pathlib.Path(root).rglob("*.cpp")):
        for name, body in tests_in(path):
            every.add(name)
            for m in SKIP.finditer(body):
                skipping.add(name)
                message = "".join(re.findall(r'"((?:[^"\\]|\\.)*)"', m.group(1)))
                claims.append((path, name, message))
    broken = []
    for path, name, message in claims:
        named = NAME.findall(message)
        if not named:
            broken.append(f"{path}: {name} skips naming no test")
        for suite, test in named:
            if test == "*":
                if not any(t.startswith(suite + ".") and t not in skipping for t in every):
                    broken.append(f"{path}: {name} names {suite}.*, and no test of it runs there")
            elif f"{suite}.{test}" not in every:
                broken.append(f"{path}: {name} names {suite}.{test}, which is no test")
            elif f"{suite}.{test}" in skipping:
                broken.append(f"{path}: {name} names {suite}.{test}, which skips itself there too")
    for b in broken:
        print(b)
    print(f"{len(claims)} skip messages, {len(broken)} broken")
    return 1 if broken else 0


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    sys.exit(main(sys.argv[1]))
