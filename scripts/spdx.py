#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
# Puts the license's SPDX line at the top of every tracked source, build and script file that lacks it (after a
# shebang); `--check` lists the files without one and exits 1 if there are any. Run from the repository root.
import subprocess
import sys

SLASH = (".cpp", ".h", ".c", ".js")
HASH = (".cmake", ".cmake.in", ".sh", ".py", ".rules", ".txt", "Makefile", ".ci/run", ".clang-format")
TAG = "SPDX-License-Identifier: MIT"


def comment(path):
    if path.endswith(SLASH):
        return "// "
    if path.endswith(HASH) and (not path.endswith(".txt") or path.endswith("CMakeLists.txt")):
        return "# "
    return None


def main():
    check = "--check" in sys.argv[1:]
    files = subprocess.run(["git", "ls-files"], capture_output=True, text=True, check=True).stdout.split("\n")
    missing = []
    for path in filter(None, files):
        prefix = comment(path)
        if prefix is None or path.startswith("tests/data/") or path.startswith("tests/fuzz/seeds/"):
            continue
        with open(path, encoding="utf-8") as f:
            text = f.read()
        if any(TAG in line for line in text.split("\n", 3)[:3]):
            continue
        missing.append(path)
        if check:
            continue
        lines = text.split("\n")
        at = 1 if lines and lines[0].startswith("#!") else 0
        lines.insert(at, prefix + TAG)
        with open(path, "w", encoding="utf-8") as f:
            f.write("\n".join(lines))
    if check:
        print("\n".join(missing))
        return 1 if missing else 0
    print(f"added the SPDX line to {len(missing)} files")
    return 0


if __name__ == "__main__":
    sys.exit(main())
