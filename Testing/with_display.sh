#!/usr/bin/env bash
# Runs a command with an X display: the one in $DISPLAY, or a private Xvfb.
# Used instead of xvfb-run, whose start-up check was seen to let the command
# start before the server listened when the machine was busy.
#   Testing/with_display.sh COMMAND [ARGUMENTS...]
set -u
if [ -n "${DISPLAY:-}" ]; then
  exec "$@"
fi
command -v Xvfb >/dev/null || { echo "with_display.sh: Xvfb is not installed (Debian package xvfb)" >&2; exit 1; }
for number in $(seq 110 199); do
  [ -e "/tmp/.X${number}-lock" ] && continue
  Xvfb ":${number}" -screen 0 1280x1024x24 -nolisten tcp >/dev/null 2>&1 &
  server=$!
  # Ready when its socket exists; gone when another run took the number first.
  for _ in $(seq 1 200); do
    [ -S "/tmp/.X11-unix/X${number}" ] && break
    kill -0 "$server" 2>/dev/null || break
    sleep 0.05
  done
  if [ -S "/tmp/.X11-unix/X${number}" ] && kill -0 "$server" 2>/dev/null; then
    DISPLAY=":${number}" "$@"
    status=$?
    kill "$server" 2>/dev/null
    wait "$server" 2>/dev/null
    exit "$status"
  fi
  kill "$server" 2>/dev/null
  wait "$server" 2>/dev/null
done
echo "with_display.sh: no X display could be started" >&2
exit 1
