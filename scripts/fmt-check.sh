#!/usr/bin/env bash
# rustfmt --check over every .rs file git tracks or would track (or every .rs file under DIR):
# `cargo fmt` reaches only the modules its `mod` lines name, and those a macro declares (the
# method registry's) are not among them. Lists each unformatted file and exits 1.
#
#   scripts/fmt-check.sh          the repository
#   scripts/fmt-check.sh DIR      the .rs files under DIR (tests/cpu/fmt_check.rs)
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
edition=$(sed -n 's/^edition = "\([0-9]*\)"/\1/p' "$root/Cargo.toml" | head -1)
if [ $# -gt 0 ]; then
  mapfile -t files < <(find "$1" -name '*.rs' -type f | sort)
else
  cd "$root"
  mapfile -t files < <({ git ls-files '*.rs'; git ls-files --others --exclude-standard '*.rs'; } | sort -u)
fi
[ ${#files[@]} -eq 0 ] && exit 0
# --check prints the diff of each file it would change; -l names them.
if ! out=$(rustfmt --edition "${edition:-2021}" --check -l "${files[@]}" 2>&1); then
  echo "rustfmt would change these files (run: rustfmt --edition ${edition:-2021} FILE, or cargo fmt --all && scripts/fmt-check.sh):" >&2
  printf '%s\n' "$out" | grep -E '\.rs$' | sort -u >&2 || printf '%s\n' "$out" >&2
  exit 1
fi
