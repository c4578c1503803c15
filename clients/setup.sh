#!/usr/bin/env bash
# Sets up what the client tests need, and does nothing that is already done:
#
# - a Python virtual environment at $CARGO_TARGET_DIR/clients-venv (target/ by default)
#   with the Python client (clients/python, editable) and the test dependencies from
#   PyPI, pinned below;
# - Debian's chromium and chromium-driver, for the viewer's browser test, when
#   /usr/bin/chromium or /usr/bin/chromedriver is missing (apt-get, as root or through
#   sudo; anything else is an error that says what to install).
#
#   bash clients/setup.sh            # prints the venv's python on its last line
#   SKIP_CHROMIUM=1 bash clients/setup.sh
set -euo pipefail
cd "$(dirname "$0")/.."
target=${CARGO_TARGET_DIR:-target}
mkdir -p "$target"
venv=$(cd "$target" && pwd)/clients-venv
# The pins, and a stamp of them: a change to either reinstalls.
requirements=(
    "httpx==0.28.1" "numpy==2.4.6" "pillow==13.0.0"
    "pytest==9.2.0" "pytest-asyncio==1.5.0" "selenium==4.51.0"
)
stamp="${requirements[*]} $( (cat clients/python/pyproject.toml 2>/dev/null || true) | sha256sum | cut -c1-16)"
if [ ! -x "$venv/bin/python" ] || [ "$(cat "$venv/.winged-stamp" 2>/dev/null)" != "$stamp" ]; then
    echo "clients/setup.sh: installing the Python test environment into $venv" >&2
    python3 -m venv "$venv"
    "$venv/bin/pip" install --quiet --disable-pip-version-check "${requirements[@]}" >&2
    if [ -f clients/python/pyproject.toml ]; then
        "$venv/bin/pip" install --quiet --disable-pip-version-check --no-deps -e clients/python >&2
    fi
    echo "$stamp" > "$venv/.winged-stamp"
fi
if [ -z "${SKIP_CHROMIUM:-}" ] && { [ ! -x /usr/bin/chromium ] || [ ! -x /usr/bin/chromedriver ]; }; then
    echo "clients/setup.sh: installing Debian's chromium and chromium-driver" >&2
    sudo=()
    [ "$(id -u)" = 0 ] || sudo=(sudo -n)
    if ! command -v apt-get >/dev/null ||
        ! { "${sudo[@]}" apt-get update -qq >&2 &&
            DEBIAN_FRONTEND=noninteractive "${sudo[@]}" apt-get install -y -qq chromium chromium-driver >&2; }; then
        echo "clients/setup.sh: could not install chromium; install Debian's chromium and chromium-driver" >&2
        exit 1
    fi
fi
echo "$venv/bin/python"
