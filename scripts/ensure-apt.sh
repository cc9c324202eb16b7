#!/usr/bin/env bash
# ensure-apt.sh CMD:PACKAGE ... — install each Debian PACKAGE whose command CMD (or,
# when CMD is an absolute path, file) is missing.
# ensure-apt.sh --install PACKAGE ... — install the packages unconditionally.
# Used by the Makefile so that `make test` / `make demo` work on a fresh Debian machine.
set -euo pipefail
missing=()
if [[ ${1:-} == --install ]]; then
  shift
  missing=("$@")
  set --
fi
for spec in "$@"; do
  cmd=${spec%%:*}
  pkg=${spec#*:}
  if [[ $cmd == /* ]]; then
    [[ -e $cmd ]] || missing+=("$pkg")
  else
    command -v "$cmd" >/dev/null 2>&1 || missing+=("$pkg")
  fi
done
[[ ${#missing[@]} -eq 0 ]] && exit 0
sudo=""
if [[ $(id -u) -ne 0 ]]; then
  command -v sudo >/dev/null || { echo "need root (or sudo) to install: ${missing[*]}" >&2; exit 1; }
  sudo=sudo
fi
echo "installing with apt-get: ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$sudo apt-get update -qq
$sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
