# Sourced by the .ci reference scripts: `make_venv DIR` creates a Python venv at
# DIR unless one is there, installing Debian's python3-venv first where the
# interpreter lacks ensurepip.
make_venv() {
    local venv=$1
    [ -x "$venv/bin/python" ] && return 0
    if ! python3 -m venv "$venv" 2>/dev/null; then
        # Debian ships venv's ensurepip separately.
        rm -rf "$venv"
        apt-get update -qq
        DEBIAN_FRONTEND=noninteractive apt-get install -y -qq python3-venv >/dev/null
        python3 -m venv "$venv"
    fi
}
