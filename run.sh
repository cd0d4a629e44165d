#!/usr/bin/env bash
# Set up a virtual environment (.venv) with the package and its test tools, then
#   bash run.sh demo       run the main job: the Table 3 simulation -> output/fig13_ode_inversion.{nc,png}
#   bash run.sh test       the test suite a developer runs in the loop (long checks marked slow left out)
#   bash run.sh test-all   every test, slow checks included (what CI runs)
#   bash run.sh docs       the documentation site, warnings as errors -> docs/_build/html/index.html
# Extra arguments after test / test-all go to pytest. The tests run in parallel (pytest-xdist), one worker per
# core, a test module's tests on one worker (its fixtures computed once); TEST_WORKERS=0 runs them in this process.
set -euo pipefail
cd "$(dirname "$0")"
PYTHON=${PYTHON:-python3}
WORKERS=${TEST_WORKERS:-auto}
if [ ! -x .venv/bin/python ]; then
    echo "run.sh: creating the virtual environment .venv ($PYTHON -m venv)"
    "$PYTHON" -m venv .venv
fi
# reinstall only when pyproject.toml changed (the install is editable: source changes need none)
stamp=".venv/.installed-$(sha256sum pyproject.toml | cut -c1-16)"
if [ ! -e "$stamp" ]; then
    echo "run.sh: installing the package with its test and documentation tools into .venv (1-2 min the first time)"
    # pip's own lines, one per package it fetches or installs; its errors go to stderr unfiltered
    .venv/bin/python -m pip install --disable-pip-version-check --progress-bar off -e ".[test,docs]" \
        | { grep --line-buffered -E "^(Collecting|Building|Installing collected|Successfully installed)" || true; }
    rm -f .venv/.installed-* && touch "$stamp"
    echo "run.sh: .venv ready; 'source .venv/bin/activate' puts tippedisk on PATH"
fi
# the CF checker of the slow tests (tests/test_cf.py): cfchecker in its own venv (it pins its own numpy),
# UDUNITS-2 from Debian
cf_checker() {
    if ! ldconfig -p | grep -q libudunits2.so.0; then
        apt-get install -y -qq libudunits2-0 >/dev/null || { apt-get update -qq && apt-get install -y -qq libudunits2-0 >/dev/null; }
    fi
    if [ ! -x .venv/cfchecker/bin/cfchecks ]; then
        "$PYTHON" -m venv .venv/cfchecker
        .venv/cfchecker/bin/python -m pip install --quiet --disable-pip-version-check cfchecker==4.1.0
    fi
}
case "${1:-demo}" in
    demo) .venv/bin/tippedisk study fig13_ode_inversion --output-dir output ;;
    test) shift; .venv/bin/python -m pytest -n "$WORKERS" --dist loadscope "$@" ;;
    test-all) shift; cf_checker; .venv/bin/python -m pytest -n "$WORKERS" --dist loadscope --slow "$@" ;;
    docs) .venv/bin/python -m sphinx -W --keep-going -q -b html docs docs/_build/html
          echo "site: docs/_build/html/index.html" ;;
    *) echo "usage: bash run.sh [demo|test|test-all [pytest args]|docs]" >&2; exit 2 ;;
esac
