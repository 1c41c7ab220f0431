#!/usr/bin/env bash
# Install LinuxCNC's G-code interpreter (Debian package linuxcnc-uspace: /usr/bin/rs274
# and the Python `gcode` module) if it is not there yet. Idempotent; needs root and
# Debian's package archive (bookworm ships 2.9.0~pre1+git20230208.f1270d6ed7).
# Measured on a fresh bookworm machine: 99 new + 24 upgraded packages, 79 MB download,
# 266 MB on disk, ~50 s with --no-install-recommends (the recommends add Qt, OpenCV, an
# RT kernel and firmware: several hundred MB more and nothing the interpreter needs).
set -euo pipefail
if [ -x /usr/bin/rs274 ] && /usr/bin/python3 -c 'import gcode' 2>/dev/null; then
  exit 0
fi
apt-get update -qq
DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends linuxcnc-uspace
/usr/bin/python3 -c 'import gcode'
test -x /usr/bin/rs274
