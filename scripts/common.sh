# Shared by scripts/demo and scripts/test: system packages and the build cache.
# shellcheck shell=bash

# One target directory for every build of this project (tests, examples,
# benches, CI), outside the checkout so a fresh clone on a warm machine
# reuses the Bevy build.
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-$HOME/.cache/bevy_chisel/target}"

say() { printf '\033[1m==> %s\033[0m\n' "$*"; }

require_cargo() {
    if ! command -v cargo >/dev/null 2>&1; then
        echo "cargo not found: install Rust first (https://rustup.rs), then run this again." >&2
        exit 1
    fi
}

# ensure_packages PKG...: installs the Debian/Ubuntu packages that are not
# installed yet (nothing to do on a second run). Elsewhere prints what to
# install and carries on.
ensure_packages() {
    local missing=()
    if command -v dpkg-query >/dev/null 2>&1; then
        local pkg
        for pkg in "$@"; do
            dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q "install ok installed" \
                || missing+=("$pkg")
        done
    else
        echo "Not a Debian/Ubuntu system: make sure these (or your distribution's equivalents)" \
             "are installed: $*" >&2
        return 0
    fi
    [ ${#missing[@]} -eq 0 ] && return 0
    local sudo=()
    if [ "$(id -u)" -ne 0 ]; then
        if command -v sudo >/dev/null 2>&1; then sudo=(sudo); else
            echo "Need root to install: ${missing[*]}; install them and run this again." >&2
            exit 1
        fi
    fi
    say "Installing system packages: ${missing[*]}"
    "${sudo[@]}" apt-get update -qq
    DEBIAN_FRONTEND=noninteractive "${sudo[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
}

# The Vulkan loader and Mesa's drivers, including lavapipe, the CPU Vulkan
# driver that renders when there is no GPU.
VULKAN_PACKAGES=(libvulkan1 mesa-vulkan-drivers)
# Libraries an X11 window loads at run time.
WINDOW_PACKAGES=(libx11-6 libxcursor1 libxi6 libxrandr2 libxkbcommon-x11-0)
