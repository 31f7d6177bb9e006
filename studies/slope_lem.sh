#!/usr/bin/env bash
# Bishop's and Spencer's factors of safety of the slope scenes with water, by XSLOPE, an
# independent limit-equilibrium package from PyPI (see studies/slope_lem.py). Installs it
# in a virtual environment under target/ (needs python3 with venv and the network to PyPI)
# and prints a Markdown table. About a minute.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
venv="$here/../target/slope-lem-venv"
if [ ! -x "$venv/bin/python" ]; then
    python3 -m venv "$venv"
    "$venv/bin/pip" install --quiet "xslope==1.0.5" openpyxl
fi
# XSLOPE reports each search's progress on stdout; the table rows start with '|'.
"$venv/bin/python" "$here/slope_lem.py" | grep '^|'
