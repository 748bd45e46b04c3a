#!/usr/bin/env bash
# The core without the GUI, as a user installs it: builds Bosun's wheel, installs it with the test tools
# but none of the GUI or joystick extras into a clean virtual environment (.core-job/venv), checks that
# PyQt5, pyqtgraph and pygame are not importable there, and runs the tests against the installed
# package (not this checkout's app/): a copy of the tests and data files without app/ and ui/.
# Usage: bash scripts/core_job.sh [--prepare | --test] [pytest args]   (default: the fast lane, -m "not slow")
#   --prepare: build, install and compile only (CI runs it beside the main suite); --test: run the tests only
set -euo pipefail
cd "$(dirname "$0")/.."
job=.core-job
PY=${PYTHON:-python3}
phase=all
case "${1:-}" in --prepare|--test) phase=${1#--}; shift ;; esac
if [ "$phase" = test ]; then
  cd "$job/tree"
  echo "core job: testing $(basename "$(ls ../dist/bosun-*.whl)") installed without the GUI extras"
  if [ $# -eq 0 ]; then set -- -m "not slow"; fi
  exec ../venv/bin/python -m pytest -p no:cacheprovider "$@"
fi
rm -rf "$job/dist" "$job/tree"
mkdir -p "$job/dist"
log="$job/build.log"
if ! "$PY" -m pip wheel --disable-pip-version-check --no-deps -w "$job/dist" . >"$log" 2>&1; then
  tail -n 30 "$log" >&2; echo "core job: building the wheel failed (log: $log)" >&2; exit 1
fi
wheel=$(ls "$job"/dist/bosun-*.whl)
[ -x "$job/venv/bin/python" ] || "$PY" -m venv "$job/venv"
# --force-reinstall --no-deps for bosun itself: the wheel of this commit, whatever was installed before.
# With uv when set-up has it (.venv/bin/uv: seconds, not a minute), else pip.
install() {
  if [ -x .venv/bin/uv ]; then .venv/bin/uv pip install --python "$job/venv/bin/python" "$@"
  else "$job/venv/bin/python" -m pip install --no-compile --disable-pip-version-check "$@"; fi
}
if ! { install "${wheel}[test]" && install --force-reinstall --no-deps "$wheel"; } >"$job/install.log" 2>&1; then
  tail -n 30 "$job/install.log" >&2; echo "core job: installing the wheel failed (log: $job/install.log)" >&2; exit 1
fi
for m in PyQt5 pyqtgraph pygame OpenGL pytestqt; do
  if "$job/venv/bin/python" -c "import $m" 2>/dev/null; then
    echo "core job: $m is importable in the core environment; it must not be" >&2; exit 1
  fi
done
# the tests, robot files, docs and README beside them, but no app/ or ui/: they import the installed wheel
mkdir -p "$job/tree"
for f in tests robots docs README.md mkdocs.yml pyproject.toml .ci scripts; do cp -r "$f" "$job/tree/"; done
find "$job/tree" -name __pycache__ -prune -exec rm -rf {} +
[ -d ../shared ] && ln -sfn "$(cd .. && pwd)/shared" "$job/shared"  # tests read ../shared/data beside the tree
cd "$job/tree"
where=$(../venv/bin/python -c "import app; print(app.__file__)")
case "$where" in
  */site-packages/*) ;;
  *) echo "core job: app imported from $where, not from the installed wheel" >&2; exit 1 ;;
esac
# the kernels this checkout's set-up compiled, where the installed file is the same (scripts/seed_kernel_cache.py)
../venv/bin/python ../../scripts/seed_kernel_cache.py ../..
../venv/bin/python -c "from app.warmup import warm_up; print(f'core job: kernels compiled or loaded ({warm_up():.1f} s)')"
echo "core job: $(basename "$wheel") installed at $where"
[ "$phase" = prepare ] && exit 0
cd ../..
exec bash scripts/core_job.sh --test "$@"
