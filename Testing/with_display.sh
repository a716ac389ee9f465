#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Runs a command with an X display: the one in $DISPLAY, or a private Xvfb.
# Used instead of xvfb-run, whose start-up check was seen to let the command
# start before the server listened when the machine was busy.
#   Testing/with_display.sh COMMAND [ARGUMENTS...]
set -u
if [ -n "${DISPLAY:-}" ]; then
  exec "$@"
fi
command -v Xvfb >/dev/null || { echo "with_display.sh: Xvfb is not installed (Debian package xvfb)" >&2; exit 1; }

# Xvfb picks a free display number itself (-displayfd) and writes it once it accepts clients.
# Choosing the number here raced when two runs started together (ctest --parallel): both took
# the same number, the second server gave up, and its command lost the display when the first
# run ended ("bad X server connection").
number_file=$(mktemp)
Xvfb -displayfd 3 -screen 0 1280x1024x24 -nolisten tcp 3>"$number_file" >/dev/null 2>&1 &
server=$!
number=""
for _ in $(seq 1 400); do
  number=$(tr -dc '0-9' <"$number_file")
  [ -n "$number" ] && break
  kill -0 "$server" 2>/dev/null || break
  sleep 0.05
done
rm -f "$number_file"
if [ -z "$number" ]; then
  kill "$server" 2>/dev/null
  wait "$server" 2>/dev/null
  echo "with_display.sh: no X display could be started" >&2
  exit 1
fi
DISPLAY=":${number}" "$@"
status=$?
kill "$server" 2>/dev/null
wait "$server" 2>/dev/null
exit "$status"
