#!/usr/bin/env bash
# Installs what genpath needs on Debian 12 or 13 when it is missing: the system packages of
# the default build (Embree, OpenImageIO, libclang for bindgen) and, if there is no cargo,
# a Rust toolchain through rustup. Run as root (or with sudo available). Idempotent.
set -euo pipefail

packages=(libembree-dev libopenimageio-dev libclang-dev pkg-config gcc g++)
packages+=("$@")   # extra packages asked for by the caller (CI adds debootstrap)

missing=()
for p in "${packages[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
    sudo=""
    [ "$(id -u)" -eq 0 ] || sudo="sudo"
    echo "setup: installing ${missing[*]}" >&2
    $sudo apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

if ! command -v cargo >/dev/null 2>&1 && [ ! -x "$HOME/.cargo/bin/cargo" ]; then
    echo "setup: no cargo found: installing Rust with rustup into ~/.cargo" >&2
    command -v curl >/dev/null 2>&1 || DEBIAN_FRONTEND=noninteractive apt-get install -y -qq curl ca-certificates >/dev/null
    curl --proto '=https' --tlsv1.2 -sSf https://sh.rustup.rs | sh -s -- -y --profile minimal
fi
echo "setup: all dependencies present" >&2
