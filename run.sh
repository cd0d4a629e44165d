#!/usr/bin/env bash
# Set up a virtual environment (.venv) with the package and its test tools, then
#   bash run.sh demo   run the main job: the Table 3 simulation -> output/fig13_ode_inversion.{nc,png}
#   bash run.sh test   run the test suite
set -euo pipefail
cd "$(dirname "$0")"
PYTHON=${PYTHON:-python3}
if [ ! -x .venv/bin/python ]; then
    "$PYTHON" -m venv .venv
fi
.venv/bin/python -m pip install --quiet --disable-pip-version-check -e ".[test]"
case "${1:-demo}" in
    demo) .venv/bin/tippedisk study fig13_ode_inversion --output-dir output ;;
    test) shift; .venv/bin/python -m pytest "$@" ;;
    *) echo "usage: bash run.sh [demo|test [pytest args]]" >&2; exit 2 ;;
esac
