#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""The house as it stands: each library's and each folder's share of the code,
the includes between the folders of a library, and the two caps on size.

    tools/layout_report.py [ROOT]

ROOT is the source tree (default: the one this script lies in). What counts
(docs/architecture.md "Size caps"): the .h, .cpp and .py files outside tests/,
docs/, build/, hidden folders and build trees (a folder with a CMakeCache.txt);
a library is a top-level folder, and a folder's files are those directly
inside it. The caps:

- no library holds more than 25 % of the lines;
- no folder holds more than 25 files.

Prints the report and exits 0 when both hold, 1 naming each offender when one
does not (or when no source is found, which is a wrong ROOT, not a pass), and 2
for bad arguments. Python 3 standard library only.
"""

import argparse
import re
import signal
import sys
from collections import defaultdict
from pathlib import Path, PurePosixPath

SUFFIXES = (".h", ".cpp", ".py")
NOT_CODE = ("tests", "docs", "build")
MAX_LIBRARY_SHARE = 25.0  # percent of all lines
MAX_FOLDER_FILES = 25  # files directly inside one folder

INCLUDE = re.compile(r'^\s*#\s*include\s*"([^"]+)"', re.M)


def is_build_tree(path):
    return (path / "CMakeCache.txt").exists()


def sources(root):
    """The counted files, as paths relative to @p root, sorted."""
    found = []
    for top in sorted(root.iterdir()):
        if not top.is_dir() or top.name.startswith(".") or top.name in NOT_CODE or is_build_tree(top):
            continue
        for path in top.rglob("*"):
            rel = path.relative_to(root)
            if any(part.startswith(".") for part in rel.parts):
                continue
            if path.suffix in SUFFIXES and path.is_file():
                found.append(PurePosixPath(rel.as_posix()))
    return sorted(found)


def line_count(path):
    with open(path, "rb") as f:
        data = f.read()
    return data.count(b"\n") + (1 if data and not data.endswith(b"\n") else 0)


def measure(root):
    """Lines per file, and the include edges between folders of one library."""
    lines = {}
    edges = defaultdict(int)  # (library, from folder, to folder) -> includes
    files = sources(root)
    tops = {f.parts[0] for f in files}
    for f in files:
        lines[f] = line_count(root / f)
        if f.suffix == ".py":
            continue
        text = (root / f).read_text(encoding="utf-8", errors="replace")
        here = f.parent
        for target in INCLUDE.findall(text):
            t = PurePosixPath(target)
            if t.parts[0] not in tops:
                continue  # a header of the same folder ("Fixtures.h"), or a third party's
            if t.parts[0] != f.parts[0] or t.parent == here:
                continue  # between libraries (the libraries' order governs those), or inside one folder
            edges[(f.parts[0], here.as_posix(), t.parent.as_posix())] += 1
    return lines, edges


def percent(part, whole):
    return 100.0 * part / whole if whole else 0.0


def report(root):
    lines, edges = measure(root)
    if not lines:
        print(f"layout: no .h, .cpp or .py files found under {root}: nothing to measure", file=sys.stderr)
        return 1
    total_lines = sum(lines.values())
    total_files = len(lines)

    library_lines = defaultdict(int)
    library_files = defaultdict(int)
    folder_lines = defaultdict(int)
    folder_files = defaultdict(int)
    for f, n in lines.items():
        library_lines[f.parts[0]] += n
        library_files[f.parts[0]] += 1
        folder_lines[f.parent.as_posix()] += n
        folder_files[f.parent.as_posix()] += 1

    out = []
    out.append(f"{total_files} files, {total_lines} lines (.h, .cpp, .py outside tests/, docs/, build/)")
    out.append("")
    out.append(f"{'library':<16}{'files':>6}{'lines':>8}{'% lines':>9}{'% files':>9}")
    for lib in sorted(library_lines, key=lambda k: (-library_lines[k], k)):
        out.append(
            f"{lib + '/':<16}{library_files[lib]:>6}{library_lines[lib]:>8}"
            f"{percent(library_lines[lib], total_lines):>9.1f}{percent(library_files[lib], total_files):>9.1f}"
        )
    out.append("")
    out.append("folder (its own files)       files   lines % lines  includes to the library's other folders")
    for folder in sorted(folder_files):
        lib = PurePosixPath(folder).parts[0]
        to = sorted(
            ((t, n) for (l, s, t), n in edges.items() if l == lib and s == folder), key=lambda e: (-e[1], e[0])
        )
        shown = ", ".join(f"{short(lib, t)} {n}" for t, n in to)
        out.append(
            f"{folder + '/':<28}{folder_files[folder]:>6}{folder_lines[folder]:>8}"
            f"{percent(folder_lines[folder], total_lines):>8.1f}  {shown}".rstrip()
        )
    out.append("")

    failures = []
    for lib, n in sorted(library_lines.items()):
        share = percent(n, total_lines)
        if share > MAX_LIBRARY_SHARE:
            failures.append(
                f"{lib}/ holds {share:.1f} % of the lines ({n} of {total_lines}); the cap is {MAX_LIBRARY_SHARE:g} %"
            )
    for folder, n in sorted(folder_files.items()):
        if n > MAX_FOLDER_FILES:
            failures.append(f"{folder}/ holds {n} files directly; the cap is {MAX_FOLDER_FILES}")
    widest_lib = max(library_lines, key=lambda k: (library_lines[k], k))
    widest_folder = max(folder_files, key=lambda k: (folder_files[k], k))
    out.append(
        f"caps: largest library {widest_lib}/ {percent(library_lines[widest_lib], total_lines):.1f} % of the lines "
        f"(cap {MAX_LIBRARY_SHARE:g} %); widest folder {widest_folder}/ {folder_files[widest_folder]} files "
        f"(cap {MAX_FOLDER_FILES}): {'over' if failures else 'within'}"
    )
    print("\n".join(out))
    for failure in failures:
        print(f"layout: {failure}", file=sys.stderr)
    return 1 if failures else 0


def short(lib, folder):
    """@p folder named inside @p lib: "." for its root, else the path below it."""
    return PurePosixPath(folder).relative_to(lib).as_posix()


def main(argv):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("root", nargs="?", default=str(Path(__file__).resolve().parent.parent), help="the source tree")
    args = parser.parse_args(argv)  # exits 2 on bad arguments
    root = Path(args.root)
    if not root.is_dir():
        print(f"layout: {root}: not a folder", file=sys.stderr)
        return 2
    return report(root)


if __name__ == "__main__":
    signal.signal(signal.SIGPIPE, signal.SIG_DFL)  # `| head` ends the listing quietly, as other tools do
    sys.exit(main(sys.argv[1:]))
