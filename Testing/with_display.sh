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
# True when an X client can open the display (libX11 comes with ParaView).
can_connect() {
  /usr/bin/python3 -c "import ctypes, sys
x = ctypes.cdll.LoadLibrary('libX11.so.6')
x.XOpenDisplay.restype = ctypes.c_void_p
d = x.XOpenDisplay(b':$1')
sys.exit(0 if d else 1)" 2>/dev/null
}

for number in $(seq 110 199); do
  # A lock or a socket left by a server that is just stopping: not free.
  [ -e "/tmp/.X${number}-lock" ] || [ -e "/tmp/.X11-unix/X${number}" ] && continue
  Xvfb ":${number}" -screen 0 1280x1024x24 -nolisten tcp >/dev/null 2>&1 &
  server=$!
  # Ready when a client can connect; gone when another run took the number first.
  ready=0
  for _ in $(seq 1 200); do
    kill -0 "$server" 2>/dev/null || break
    if can_connect "$number"; then
      ready=1
      break
    fi
    sleep 0.05
  done
  if [ "$ready" = 1 ]; then
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
