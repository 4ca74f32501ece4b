# SPDX-License-Identifier: Apache-2.0
"""tools/layout_report.py on small trees built here, whose shares and counts are
known by construction: each cap holds at its limit and fails one past it,
naming the offender; what is not code is not counted; the include edges
between a library's folders are the ones written; and a tree without sources
fails rather than passing with nothing measured."""

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

SCRIPT = Path(os.environ.get("VOXHAP_SOURCE_DIR", Path(__file__).resolve().parents[2])) / "tools" / "layout_report.py"


def write(root, rel, lines):
    """A file of exactly @p lines lines."""
    path = root / rel
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("".join(f"// {i}\n" for i in range(lines)))


def run(root):
    return subprocess.run([sys.executable, str(SCRIPT), str(root)], capture_output=True, text=True, timeout=60)


def libraries(root, sizes):
    """One file per library, of the given line counts."""
    for name, lines in sizes.items():
        write(root, f"{name}/{name.capitalize()}.cpp", lines)


def test_a_library_at_a_quarter_of_the_lines_passes(tmp_path):
    libraries(tmp_path, {"a": 100, "b": 100, "c": 100, "d": 100})
    result = run(tmp_path)
    assert result.returncode == 0, result.stderr
    assert "a/                   1     100     25.0" in result.stdout


def test_a_library_above_a_quarter_of_the_lines_fails_naming_it(tmp_path):
    libraries(tmp_path, {"a": 101, "b": 100, "c": 100, "d": 100})
    result = run(tmp_path)
    assert result.returncode == 1
    # 101 / 401 = 25.19 %
    assert "layout: a/ holds 25.2 % of the lines (101 of 401); the cap is 25 %" in result.stderr
    assert "b/" not in result.stderr


def test_a_folder_of_25_files_passes_and_26_fail_naming_it(tmp_path):
    libraries(tmp_path, {"b": 100, "c": 100, "d": 100, "e": 100})
    for i in range(25):
        write(tmp_path, f"a/wide/F{i}.h", 1)
    write(tmp_path, "a/wide/sub/Below.h", 1)  # in a subfolder: not one of wide/'s own files
    assert run(tmp_path).returncode == 0
    write(tmp_path, "a/wide/F25.py", 1)
    result = run(tmp_path)
    assert result.returncode == 1
    assert result.stderr.strip() == "layout: a/wide/ holds 26 files directly; the cap is 25"


def test_tests_docs_build_trees_and_other_suffixes_are_not_counted(tmp_path):
    libraries(tmp_path, {"a": 10, "b": 10, "c": 10, "d": 10})
    for folder in ("tests", "docs", "build", ".git"):
        write(tmp_path, f"{folder}/Huge.cpp", 1000)
    write(tmp_path, "build-debug/CMakeCache.txt", 1)
    write(tmp_path, "build-debug/Huge.cpp", 1000)
    write(tmp_path, "a/notes.md", 1000)
    write(tmp_path, "a/.hidden/Huge.cpp", 1000)
    result = run(tmp_path)
    assert result.returncode == 0, result.stderr
    assert result.stdout.startswith("4 files, 40 lines")


def test_include_edges_between_one_librarys_folders(tmp_path):
    libraries(tmp_path, {"b": 100, "c": 100, "d": 100, "e": 100})
    (tmp_path / "a/low").mkdir(parents=True)
    (tmp_path / "a/high").mkdir(parents=True)
    (tmp_path / "a/low/Low.h").write_text('#include "b/B.h"\n')  # another library's: not an edge
    (tmp_path / "a/high/High.cpp").write_text(
        '#include "a/high/High.h"\n#include "a/low/Low.h"\n#include "a/low/Low.h"\n#include "a/Root.h"\n'
        "#include <vector>\n"
    )
    (tmp_path / "a/Root.h").write_text("#pragma once\n")
    result = run(tmp_path)
    assert result.returncode == 0, result.stderr
    rows = {line.split()[0]: line for line in result.stdout.splitlines() if line.startswith("a/")}
    assert rows["a/high/"].endswith("low 2, . 1")
    assert rows["a/low/"].split()[1:] == ["1", "1", "0.2"]  # one file, one line, no edge


def test_a_tree_without_sources_fails(tmp_path):
    write(tmp_path, "docs/Only.cpp", 10)
    result = run(tmp_path)
    assert result.returncode == 1
    assert "no .h, .cpp or .py files found" in result.stderr


def test_a_missing_root_is_a_bad_argument(tmp_path):
    result = run(tmp_path / "absent")
    assert result.returncode == 2
    assert result.stderr.strip() == f"layout: {tmp_path / 'absent'}: not a folder"


ROW = re.compile(r"^([a-z0-9_.-]+(?:/[a-z0-9_.-]+)*/) +\d", re.M)


def folders_named(listing):
    """The libraries and folders the report's rows name."""
    return set(ROW.findall(listing))


def test_readme_shows_every_folder():
    """The README's "Layout" shows the report: its figures are a snapshot, but
    the folders it lists are the tree's, every one."""
    root = SCRIPT.parent.parent
    readme = (root / "README.md").read_text(encoding="utf-8")
    start = readme.index("$ tools/layout_report.py\n")
    shown = folders_named(readme[start : readme.index("```", start)])
    measured = folders_named(run(root).stdout)
    assert len(measured) > 30  # the rows were found: an empty match is not agreement
    assert sorted(measured - shown) == [], "folders the README's listing lacks"
    assert sorted(shown - measured) == [], "folders the README lists that the tree no longer has"


if __name__ == "__main__":
    sys.exit(pytest.main([__file__, "-q"]))
