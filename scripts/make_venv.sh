#!/usr/bin/env bash
# Builds (or reuses) the Python 3.12 venv in .venv/ and installs sortbot with its pinned stack.
# Re-runs the install only when pyproject.toml changed since the last successful one.
set -euo pipefail
VENV=${VENV:-.venv}
stamp="$VENV/.sortbot-installed"
want=$(sha256sum pyproject.toml | cut -c1-16)
if [ -x "$VENV/bin/python" ] && [ -f "$stamp" ] && [ "$(cat "$stamp")" = "$want" ]; then
  exit 0
fi
if [ ! -x "$VENV/bin/python" ]; then
  py=""
  for cand in "$(PYENV_VERSION=3.12.1 pyenv which python3.12 2>/dev/null || true)" "$(command -v python3.12 || true)"; do
    if [ -n "$cand" ] && "$cand" -c 'import sys; assert sys.version_info[:2] == (3, 12)' 2>/dev/null; then py=$cand; break; fi
  done
  [ -n "$py" ] || { echo "sortbot: Python 3.12 not found (lerobot >= 0.5 needs it); install it (pyenv install 3.12) and retry" >&2; exit 1; }
  echo "sortbot: creating $VENV with $py"
  "$py" -m venv "$VENV"
fi
"$VENV/bin/python" -m pip install -q --upgrade pip
echo "sortbot: installing the stack into $VENV (first time: a few minutes, ~5 GB)"
"$VENV/bin/python" -m pip install -q --progress-bar off -e ".[dev]"
# ultralytics pulls opencv-python, lerobot opencv-python-headless: both ship cv2 and clash.
# Keep exactly one working cv2: the headless one (no GUI needed, no X libraries).
if "$VENV/bin/python" -m pip show -q opencv-python >/dev/null 2>&1; then
  headless=$("$VENV/bin/python" -m pip show opencv-python-headless 2>/dev/null | awk '/^Version:/{print $2}')
  "$VENV/bin/python" -m pip uninstall -q -y opencv-python
  "$VENV/bin/python" -m pip install -q --force-reinstall --no-deps "opencv-python-headless${headless:+==$headless}"
fi
"$VENV/bin/python" -c "import cv2, mujoco, sortbot" 
echo "$want" > "$stamp"
