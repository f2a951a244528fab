#!/bin/sh
# Runs the workbench's GUI test: run-gui-test.sh PROGRAM [DISPLAY-WRAPPER ARGS...]
# (for example xvfb-run -a -s "-screen 0 1920x1200x24").
#
# QtTest's watchdog stops a test function that has not returned within
# QTEST_FUNCTION_TIMEOUT and prints every thread's stack. Under Xvfb with Mesa's software
# OpenGL, about one run in ten has stopped that way while the simulation ran: the GUI thread
# blocked inside Mesa while compositing the window's OpenGL views (llvmpipe: waiting on a
# fence its idle rasteriser threads never signal; softpipe: busy in it), the X server idle,
# the simulation still stepping. That is a stall of the software renderer, not a result of
# the test: a run stopped by the watchdog is run again, up to three runs. A failed check, a
# crash, or three stalls in a row fail the test.
set -u
program=$1
shift
log=$(mktemp) || exit 2
trap 'rm -f "$log"' EXIT
# A test function takes a few seconds; 90 s leaves room for a loaded machine.
: "${QTEST_FUNCTION_TIMEOUT:=90000}"
export QTEST_FUNCTION_TIMEOUT
attempt=1
while :; do
  "$@" "$program" > "$log" 2>&1
  status=$?
  cat "$log"
  if [ "$status" -eq 0 ] || ! grep -q "Test function timed out" "$log" || [ "$attempt" -ge 3 ]; then
    exit "$status"
  fi
  attempt=$((attempt + 1))
  echo "run-gui-test: the run stalled (stopped by the watchdog); run $attempt of at most 3"
done
