#!/bin/sh
# The system packages the tests need, on Debian or Ubuntu: Chromium for the browser tests
# (Playwright drives /usr/bin/chromium; no browser is ever downloaded) and BLAS/LAPACK, which
# OpenSeesPy's shared library loads (the FE tests). Installs what is missing with apt-get, as
# root or through sudo. Where that cannot be done it says why and exits 0: the suite then skips
# the tests that need the missing packages, naming them. --strict (CI) exits 1 instead.
set -u
PACKAGES="chromium libopenblas0 liblapack3"
NAME="install_system_packages"
strict=0
[ "${1:-}" = "--strict" ] && strict=1

give_up() {
    echo "$NAME: $1" >&2
    [ "$strict" = 1 ] && exit 1
    echo "$NAME: the tests that need them will be skipped, and the test report says why" >&2
    exit 0
}

if ! command -v apt-get >/dev/null 2>&1 || ! command -v dpkg-query >/dev/null 2>&1; then
    give_up "no apt-get here (not Debian or Ubuntu): install $PACKAGES by hand"
fi
missing=""
for package in $PACKAGES; do
    dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "ok installed" \
        || missing="$missing $package"
done
if [ -z "$missing" ]; then
    echo "$NAME: $PACKAGES are installed"
    exit 0
fi
if [ "$(id -u)" = 0 ]; then
    sudo=""
elif command -v sudo >/dev/null 2>&1; then
    sudo="sudo"
else
    give_up "not root and no sudo: as root, run apt-get install -y$missing"
fi
echo "$NAME: installing$missing"
$sudo apt-get update -qq || give_up "apt-get update failed: install$missing by hand"
available=""
unavailable=""
for package in $missing; do
    if [ -n "$(apt-cache policy "$package" 2>/dev/null | grep 'Candidate:' | grep -v '(none)')" ]
    then
        available="$available $package"
    else
        unavailable="$unavailable $package"
        echo "$NAME: no package $package here (Ubuntu ships Chromium as a snap: the browser" \
            "tests use /usr/bin/chromium, or the browser named by TUNNELSETTLE_CHROMIUM)" >&2
    fi
done
if [ -n "$available" ]; then
    # shellcheck disable=SC2086  # the package list is split on purpose
    $sudo env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq $available >/dev/null \
        || give_up "apt-get could not install$available"
fi
[ -n "$available" ] && echo "$NAME: installed$available"
[ -z "$unavailable" ] || give_up "not installed:$unavailable"
