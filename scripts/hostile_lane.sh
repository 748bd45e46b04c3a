#!/usr/bin/env bash
# The hostile lane (issue 28): the fast lane (-m "not slow") once more on a machine unlike the developer's,
# so that no test passes only because of where, as whom, or when it runs:
#   * pytest's --basetemp is long (> 150 characters) and holds a space and a non-ASCII letter ("Øvelse 1");
#   * LANG=C.UTF-8 (no LC_ALL, no LC_*), TZ=Pacific/Chatham (UTC+12:45/+13:45: a quarter-hour offset);
#   * run as root (CI), it runs as an unprivileged user (nobody), HOME and TMPDIR in a folder of its own;
#   * from that HOME, not from the checkout (no test may find a file by the working directory).
# nobody may not be able to read the checkout, its .venv or the interpreter the venv was made from (pyenv
# under /root: mode 700), so when run as root the lane stages them in a temporary folder first: hard links
# (a second copy only when the temporary folder is on another file system), the staged folders owned by the
# lane's user, the venv's absolute paths (pyvenv.cfg, bin/ scripts and links, the editable install's finder)
# rewritten to the staged copies.  Nothing of the checkout is changed, and the staging is removed at the end.
# Usage: bash scripts/hostile_lane.sh [--core] [pytest args]      (default: -m "not slow")
#   --core: the core job's tree and venv (scripts/core_job.sh --prepare made them: the wheel without the GUI
#   extras), not this checkout and .venv.  CI runs the core job's fast lane this way: one lane that is both
#   the second run of the fast lane and the hostile one (issue 28, item 5: CI in five minutes).
#   HOSTILE_USER=name: the user to run as when root (default nobody); HOSTILE_KEEP=1 keeps the staging folder.
set -uo pipefail
cd "$(dirname "$0")/.."
if [ "${1:-}" = --core ]; then
  shift
  [ -x .core-job/venv/bin/python ] && [ -d .core-job/tree ] ||
    { echo "hostile lane: no core job to test (run scripts/core_job.sh --prepare)" >&2; exit 1; }
  cd .core-job/tree
  venv=$(cd ../venv && pwd -P)
  what="the core job (the wheel without the GUI extras)"
else
  [ -x .venv/bin/python ] || { echo "hostile lane: no .venv (run scripts/setup.sh)" >&2; exit 1; }
  venv=$(cd .venv && pwd -P)
  what="this checkout"
fi
repo=$(pwd -P)
[ $# -eq 0 ] && set -- -m "not slow"
base=$("$venv/bin/python" -c 'import sys; print(sys.base_prefix)') || exit 1
base=$(cd "$base" && pwd -P)

stage=$(mktemp -d "${TMPDIR:-/tmp}/bosun-hostile.XXXXXX") || exit 1
[ "${HOSTILE_KEEP:-0}" = 1 ] || trap 'rm -rf "$stage"' EXIT
chmod 755 "$stage"
mkdir -p "$stage/home" "$stage/tmp" "$stage/run"
chmod 700 "$stage/run"  # XDG_RUNTIME_DIR, as a login gives a user
# the base temporary folder: > 150 characters, a space, a non-ASCII letter
long="$stage/tmp/Øvelse 1/bosun hostile lane – a temporary folder whose path is long, has spaces and a letter beyond ASCII"
while [ "$(printf %s "$long" | wc -m)" -lt 160 ]; do long+="_"; done
mkdir -p "$(dirname "$long")"  # pytest makes the base folder itself, not its parents

run_as=()
if [ "$(id -u)" -eq 0 ]; then
  user=${HOSTILE_USER:-nobody}
  uid=$(id -u "$user") && gid=$(id -g "$user") || { echo "hostile lane: no user $user" >&2; exit 1; }
  run_as=(setpriv --reuid="$uid" --regid="$gid" --clear-groups --)
  command -v setpriv >/dev/null || run_as=(runuser -u "$user" --)
  can() { "${run_as[@]}" "$@" >/dev/null 2>&1; }
  # a tree the lane's user can read and write in: hard links to the files, folders of its own
  link_copy() {  # link_copy SRC DST: DST a copy of SRC whose folders belong to the lane's user
    if ! cp -al "$1" "$2" 2>/dev/null; then
      rm -rf "$2" && cp -a "$1" "$2" && chown -R "$uid:$gid" "$2" && return
    fi
    find "$2" -type d -exec chown "$uid:$gid" {} +  # the folders are new; the linked files stay as they are
  }
  work="$stage/bosun"
  mkdir "$work"
  for f in "$repo"/* "$repo"/.[!.]*; do
    case "$(basename "$f")" in .venv|.core-job|.git|.pytest_cache|.hypothesis|build|*.egg-info) continue ;; esac
    link_copy "$f" "$work/$(basename "$f")" || exit 1
  done
  chown "$uid:$gid" "$work"  # not -R: below it are the hard links, which are the checkout's own files
  chown -R "$uid:$gid" "$stage/home" "$stage/tmp" "$stage/run"  # only folders made here
  # ../shared (test data beside the checkout) as the tests find it, when there is one
  if [ -d "$repo/../shared" ]; then
    if can test -r "$repo/../shared/data" -a -x "$repo/../shared/data"; then
      ln -s "$(cd "$repo/../shared" && pwd -P)" "$stage/shared"
    else
      link_copy "$(cd "$repo/../shared" && pwd -P)" "$stage/shared"
    fi
  fi
  # the venv and the interpreter it was made from, staged when the lane's user cannot use them where they are
  # (an interpreter it cannot read may still start, on another stdlib: check that it can read this one's)
  stdlib=$("$venv/bin/python" -c 'import os; print(os.path.realpath(os.__file__))') || exit 1
  newbase=$base
  if ! can test -r "$stdlib"; then
    newbase="$stage/python"
    link_copy "$base" "$newbase" || exit 1
  fi
  link_copy "$venv" "$work/.venv" || exit 1
  "$venv/bin/python" - "$work/.venv" "$venv=$work/.venv" "$repo=$work" "$base=$newbase" <<'EOF' || exit 1
import os, sys
from pathlib import Path
venv, pairs = Path(sys.argv[1]), [a.split("=", 1) for a in sys.argv[2:]]
pairs.sort(key=lambda p: -len(p[0]))  # the venv inside the checkout first
def moved(s):
    for old, new in pairs:
        if s == old or s.startswith(old + "/"):
            return new + s[len(old):]
    return s
def rewrite(p):
    data = p.read_bytes()
    new = data
    for old, repl in pairs:
        new = new.replace(old.encode(), repl.encode())
    if new != data:
        mode = p.stat().st_mode
        p.unlink()  # a new file, not the linked one: the original stays as it is
        p.write_bytes(new)
        os.chmod(p, mode)
for p in (venv / "bin").iterdir():
    if p.is_symlink():
        target = os.readlink(p)
        if os.path.isabs(target) and moved(target) != target:
            p.unlink()
            p.symlink_to(moved(target))
    elif p.is_file() and p.stat().st_size < 1 << 20:
        rewrite(p)
rewrite(venv / "pyvenv.cfg")
for site in venv.glob("lib/python*/site-packages"):
    for p in list(site.glob("*.pth")) + list(site.glob("__editable__*.py")):
        rewrite(p)
EOF
  check="import sys, pytest, numpy; sys.exit(sys.base_prefix != sys.argv[1])"
  if ! can env LD_LIBRARY_PATH="$newbase/lib" "$work/.venv/bin/python" -c "$check" "$newbase"; then
    echo "hostile lane: $user cannot run the staged venv ($work/.venv)" >&2
    "${run_as[@]}" env LD_LIBRARY_PATH="$newbase/lib" "$work/.venv/bin/python" -c "$check; print(sys.base_prefix)" "$newbase" >&2
    exit 1
  fi
  extra_env=(LD_LIBRARY_PATH="$newbase/lib")
  echo "hostile lane: $what, as $user (uid $uid) in a staged copy: $work"
  python="$work/.venv/bin/python"
else
  user=$(id -un 2>/dev/null || id -u)
  work=$repo
  extra_env=()
  echo "hostile lane: $what, as $user (not root: no other user to run as) in $work"
  python="$venv/bin/python"
fi
chmod 1777 "$stage/tmp"
echo "hostile lane: --basetemp '$long' ($(printf %s "$long" | wc -m) characters), LANG=C.UTF-8, TZ=Pacific/Chatham"
# from the user's home, not the checkout: no test may find a file by the working directory.  Test paths given
# relative to the checkout (tests/test_cli.py::name) are made absolute; without any, the whole of tests/.
args=() paths=0
for a in "$@"; do
  if [[ "$a" != -* && -e "$work/${a%%::*}" ]]; then args+=("$work/$a"); paths=1; else args+=("$a"); fi
done
[ "$paths" = 1 ] || args+=("$work/tests")
cd "$stage/home" || exit 1
start=$(date +%s)
"${run_as[@]}" env -i PATH="/usr/local/bin:/usr/bin:/bin:/usr/sbin:/sbin" HOME="$stage/home" USER="$user" \
  LOGNAME="$user" TMPDIR="$stage/tmp" XDG_RUNTIME_DIR="$stage/run" LANG=C.UTF-8 TZ=Pacific/Chatham "${extra_env[@]}" \
  "$python" -m pytest -p no:cacheprovider --rootdir "$work" -c "$work/pyproject.toml" \
  --basetemp "$long" "${args[@]}"
rc=$?
echo "hostile lane: exit $rc in $(( $(date +%s) - start )) s"
exit $rc
