#!/usr/bin/env bash
# Set up weather-mi in this checkout: Debian's libllvm19 (Dr.Jit's LLVM backend needs LLVM >= 16) and
# chromium (browser tests of the viewer),
# a virtualenv in .venv, and the package with its test extras at the versions of constraints.txt.
# Idempotent; quick when already done.
set -euo pipefail
cd "$(dirname "$0")"

if ! ls /usr/lib/x86_64-linux-gnu/libLLVM.so.19* >/dev/null 2>&1 \
   && ! ls /usr/lib/*/libLLVM-19.so* >/dev/null 2>&1; then
  echo "[setup] installing Debian's libllvm19 (Dr.Jit needs LLVM >= 16)"
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq libllvm19 >/dev/null
fi

if ! command -v chromium >/dev/null 2>&1; then
  echo "[setup] installing Debian's chromium (the viewer's browser tests drive it through Playwright)"
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq chromium >/dev/null
fi

PY=${PYTHON:-python3}
if [ ! -x .venv/bin/python ]; then
  echo "[setup] creating .venv"
  "$PY" -m venv .venv
fi

stamp=.venv/.weather-mi-installed
if [ ! -f "$stamp" ] || [ pyproject.toml -nt "$stamp" ] || [ constraints.txt -nt "$stamp" ]; then
  echo "[setup] installing weather-mi with test extras (versions pinned by constraints.txt)"
  .venv/bin/python -m pip install -q --upgrade pip
  .venv/bin/python -m pip install -q -c constraints.txt -e ".[test]"
  touch "$stamp"
fi
