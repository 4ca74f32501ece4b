#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Checks docs/guide.md against the program it describes.
#
#   CheckGuide.sh SOURCE_DIR VOXHAP pictures   the guide's image links are the
#       set docs/guide/make-pictures.sh makes, and each is in docs/guide/img
#   CheckGuide.sh SOURCE_DIR VOXHAP commands   every `build/bin/voxhap SUB ...`
#       line of the guide names a subcommand that exists and only options its
#       --help lists
#   CheckGuide.sh SOURCE_DIR VOXHAP regenerate  make-pictures.sh runs to the
#       end into a scratch folder and makes every picture (needs the shared CT;
#       exit 77, skipped, without it unless VOXHAP_REQUIRE_SHARED_DATA or
#       VOXHAP_REQUIRE_ALL is set)
set -euo pipefail
src=$1 voxhap=$2 what=$3
guide=$src/docs/guide.md
script=$src/docs/guide/make-pictures.sh
fail() { echo "CheckGuide: $*" >&2; exit 1; }

case $what in
pictures)
  linked=$(grep -o '](guide/img/[^)]*)' "$guide" | sed 's/^](guide\/img\///; s/)$//' | sort)
  made=$("$script" --list | sort)
  [ -n "$linked" ] || fail "docs/guide.md links no picture"
  if [ "$linked" != "$made" ]; then
    fail "docs/guide.md links [$(echo $linked)] but make-pictures.sh makes [$(echo $made)]"
  fi
  for p in $linked; do
    [ -s "$src/docs/guide/img/$p" ] || fail "docs/guide/img/$p is missing (run docs/guide/make-pictures.sh)"
    # A PNG, not a placeholder: the signature and a size no blank picture has.
    [ "$(head -c 8 "$src/docs/guide/img/$p" | od -An -tx1 | tr -d ' \n')" = 89504e470d0a1a0a ] ||
      fail "docs/guide/img/$p is not a PNG"
    [ "$(stat -c %s "$src/docs/guide/img/$p")" -gt 10000 ] || fail "docs/guide/img/$p is under 10 kB"
  done
  echo "CheckGuide: $(echo "$linked" | wc -l) pictures linked, made by the script and present"
  ;;
commands)
  n=0
  declare -A helps=()
  # --help of "SUB" or "SUB SUB2", asked once each (the program starts in about 0.2 s).
  help_of() {
    local key="$*"
    if [ -z "${helps[$key]+set}" ]; then
      helps[$key]=$("$voxhap" "$@" --help 2>&1) || return 1
    fi
    printf '%s\n' "${helps[$key]}"
  }
  # Command lines inside the guide's sh blocks; a trailing comment and a
  # trailing & are not part of the command.
  while IFS= read -r line; do
    line=${line%%#*}
    line=${line%&*}
    read -r -a words <<<"$line"
    sub=${words[1]:-}
    [ -n "$sub" ] || fail "a guide line runs voxhap with no subcommand: '$line'"
    help_of "$sub" >/dev/null || fail "voxhap $sub: no such subcommand (guide line: '$line')"
    help=$(help_of "$sub")
    # A second word that SUB lists as a subcommand of its own (bench sampler, batch merge).
    if [ "${#words[@]}" -gt 2 ] && grep -q "^Subcommands:" <<<"$help" &&
      grep -Eq "^  ${words[2]}( |$)" <<<"$help"; then
      sub="$sub ${words[2]}"
      help=$(help_of $sub)
    fi
    for w in "${words[@]:2}"; do
      [[ $w == --* ]] || continue
      opt=${w%%=*}
      grep -Eq -- "(^|[ ,])$opt([ ,=]|$)" <<<"$help" || fail "voxhap $sub has no option $opt (guide line: '$line')"
    done
    n=$((n + 1))
  done < <(awk '/^```sh/{b=1; next} /^```/{b=0} b' "$guide" | grep -E '^build/bin/voxhap ')
  [ "$n" -gt 10 ] || fail "only $n voxhap command lines found in docs/guide.md"
  echo "CheckGuide: $n command lines name existing subcommands and options"
  ;;
regenerate)
  ct=$src/../shared/data/ct-abdomen-tcia/dicom
  if [ ! -d "$ct" ]; then
    [ -z "${VOXHAP_REQUIRE_SHARED_DATA:-}${VOXHAP_REQUIRE_ALL:-}" ] || fail "no shared CT at $ct"
    echo "CheckGuide: no shared CT; skipped"
    exit 77
  fi
  out=$(mktemp -d)
  trap 'rm -rf "$out"' EXIT
  VOXHAP_BUILD_DIR=$(cd "$(dirname "$voxhap")/.." && pwd) "$script" --out "$out" --ct "$ct"
  for p in $("$script" --list); do
    [ -s "$out/$p" ] || fail "make-pictures.sh did not make $p"
  done
  echo "CheckGuide: make-pictures.sh made every picture"
  ;;
*) fail "unknown check '$what'" ;;
esac
