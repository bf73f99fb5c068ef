#!/usr/bin/env bash
# Install the Debian packages named on the command line unless all of them are installed already.
#   scripts/apt-ensure.sh LABEL [--optional] PKG...
# LABEL names the set in the messages ("packages", "test packages"). With --optional a failed installation
# is reported and tolerated (the tests that need the packages skip themselves); without it, it fails.
set -u
label=$1; shift
optional=0
if [ "${1:-}" = --optional ]; then optional=1; shift; fi
n_ok=$(dpkg-query -W -f='${Status}\n' "$@" 2>/dev/null | grep -c '^install ok installed$')
if [ "$n_ok" -eq "$#" ]; then
  echo "apt: $label present"
  exit 0
fi
echo "apt: installing $label: $*"
SUDO=$([ "$(id -u)" = 0 ] || echo sudo)
if $SUDO apt-get update -qq && DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "$@"; then
  exit 0
fi
if [ "$optional" = 1 ]; then
  echo "apt: $label not installed: the tests that need them will be skipped"
  exit 0
fi
exit 1
