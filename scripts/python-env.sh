#!/usr/bin/env bash
# Creates (once) the project's Python venv in .venv with the packages the tests and tools use.
set -euo pipefail
cd "$(dirname "$0")/.."
if [ ! -x .venv/bin/python ]; then
  python3 -m venv .venv
fi
.venv/bin/python -m pip install -q --disable-pip-version-check -r python/requirements.txt
