#!/usr/bin/env bash
# Installs everything Bosun needs on a Debian machine (run as root for the system packages):
#   * Debian packages for Qt's xcb platform, Mesa OpenGL and Xvfb (skipped when present or not root),
#   * a virtual environment .venv/ with Bosun, its test tools and the docs site's MkDocs installed from
#     pyproject.toml (the extra all).
# Safe to run again: it only installs what is missing.
set -euo pipefail
cd "$(dirname "$0")/.."

DEBS=(xvfb xauth libgl1 libglx-mesa0 libgl1-mesa-dri libegl1 libfontconfig1 libxkbcommon-x11-0
      libx11-xcb1 libxcb-icccm4 libxcb-image0 libxcb-keysyms1 libxcb-randr0 libxcb-render-util0
      libxcb-shape0 libxcb-xinerama0 libxcb-xfixes0 libxcb-xkb1 libxcb-glx0 libxcb-sync1
      libxcb-shm0 libxcb-util1 libdbus-1-3)

if command -v apt-get >/dev/null 2>&1 && command -v dpkg-query >/dev/null 2>&1; then
  missing=()
  for p in "${DEBS[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  if ((${#missing[@]})); then
    if [ "$(id -u)" -eq 0 ]; then
      echo "setup: installing Debian packages: ${missing[*]}"
      apt-get update -qq
      DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
    else
      echo "setup: not root; skipping Debian packages (${missing[*]}); the GUI may need them" >&2
    fi
  fi
fi

PY=${PYTHON:-python3}
if [ ! -x .venv/bin/python ]; then
  if ! "$PY" -m venv .venv 2>/dev/null; then
    if [ "$(id -u)" -eq 0 ] && command -v apt-get >/dev/null 2>&1; then
      DEBIAN_FRONTEND=noninteractive apt-get install -y -qq python3-venv >/dev/null
      rm -rf .venv && "$PY" -m venv .venv
    else
      echo "setup: '$PY -m venv' failed; install python3-venv" >&2
      exit 1
    fi
  fi
fi
log=.venv/setup-pip.log
# uv installs from its cache in about 10 s what pip takes 75-120 s for (2-core VM, 2026-11-28: the same
# versions); pip when uv cannot be had.  No byte-compiling ahead: Python compiles what it imports, once.
if .venv/bin/python -m pip install -q --disable-pip-version-check uv >"$log" 2>&1 &&
   .venv/bin/uv pip install --python .venv/bin/python -e '.[all]' >>"$log" 2>&1; then
  :
elif ! .venv/bin/python -m pip install --no-compile --disable-pip-version-check -e '.[all]' >>"$log" 2>&1; then
  tail -n 30 "$log" >&2
  echo "setup: pip install failed (full log: $log)" >&2
  exit 1
fi
PYGAME_HIDE_SUPPORT_PROMPT=1 .venv/bin/python -c "import app, numpy, scipy, lxml, PyQt5, pyqtgraph, pygame, capytaine, distributed, mkdocs, material" \
  || { echo "setup: installed packages do not import" >&2; exit 1; }
# compile ahead: numba caches the kernels' machine code on disk, so no engine compiles in its first tick
.venv/bin/python -c "import os; from app.warmup import warm_up; t = warm_up(workers=len(os.sched_getaffinity(0))); print(f'setup: kernels compiled ({t:.1f} s)')" \
  || { echo "setup: compiling the kernels failed" >&2; exit 1; }
echo "setup: ready (.venv)"
