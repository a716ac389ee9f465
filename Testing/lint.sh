#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# The project's hygiene checks, run by the test suite (ctest -R Lint):
#   lint.sh format <source dir>               every C++ file as .clang-format says
#   lint.sh spdx <source dir>                 every source file names its licence (SPDX)
#   lint.sh tidy <source dir> <build dir>     .clang-tidy's checks on the algorithm core
#   lint.sh size <source dir>                 no file of the algorithm core over 800 lines
# Exits 77 (ctest: skipped) when the tool it needs is not installed.
set -euo pipefail
check=$1
source_dir=$2
cd "$source_dir"
# The project's files: in a git checkout those tracked or new (not ignored) that exist (a deletion
# may not be staged yet); in a source archive every file but what .gitignore leaves out (build
# folders, results, Python caches). Each pattern is a path glob: '*.h', 'Filters/Algorithms/*/*.cxx'.
project_files() {
  if git rev-parse --is-inside-work-tree >/dev/null 2>&1; then
    git ls-files --cached --others --exclude-standard "$@" | sort -u | while read -r f; do [ -f "$f" ] && echo "$f"; done
    return
  fi
  local f pattern
  find . -type f -not -path './build*' -not -path './results/*' -not -path '*/__pycache__/*' \
    -not -path './.git/*' | sed 's|^\./||' | while read -r f; do
    for pattern in "$@"; do
      # A pattern without a slash matches the file's name in any folder, as git's does.
      case "$pattern" in
        */*) if [[ "$f" == $pattern ]]; then echo "$f"; break; fi ;;
        *) if [[ "${f##*/}" == $pattern ]]; then echo "$f"; break; fi ;;
      esac
    done
  done | sort -u
}
cxx_files() { project_files '*.h' '*.cxx'; }

case "$check" in
  format)
    command -v clang-format >/dev/null || { echo "clang-format is not installed: skipped"; exit 77; }
    cxx_files | xargs clang-format --dry-run --Werror
    echo "every C++ file is formatted as .clang-format says"
    ;;
  spdx)
    missing=0
    for f in $(project_files '*.h' '*.cxx' '*.py' '*.sh' '*.xml' '*CMakeLists.txt' .ci/run); do
      if ! head -n 3 "$f" | grep -q "SPDX-License-Identifier: BSD-3-Clause"; then
        echo "$f: no SPDX-License-Identifier line at its top"
        missing=1
      fi
    done
    [ "$missing" -eq 0 ] && echo "every source file names its licence"
    exit "$missing"
    ;;
  tidy)
    build_dir=$3
    command -v clang-tidy >/dev/null || { echo "clang-tidy is not installed: skipped"; exit 77; }
    [ -f "$build_dir/compile_commands.json" ] || { echo "no $build_dir/compile_commands.json" >&2; exit 1; }
    project_files 'Filters/Algorithms/*/*.cxx' | xargs -P "$(nproc)" -n 1 clang-tidy -p "$build_dir" --quiet
    echo "clang-tidy finds nothing in the algorithm core"
    ;;
  size)
    # A module that outgrows this is split by what it does (docs/DESIGN.md, the stage table).
    largest=800
    long=0
    for f in $(project_files 'Filters/Algorithms/*/*.h' 'Filters/Algorithms/*/*.cxx'); do
      lines=$(wc -l <"$f")
      if [ "$lines" -gt "$largest" ]; then
        echo "$f: $lines lines, over $largest"
        long=1
      fi
    done
    [ "$long" -eq 0 ] && echo "no file of the algorithm core is over $largest lines"
    exit "$long"
    ;;
  *)
    echo "unknown check '$check': format, spdx, tidy or size" >&2
    exit 2
    ;;
esac
