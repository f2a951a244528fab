#!/bin/sh
# Runs the workbench's GUI test: run-gui-test.sh PROGRAM [DISPLAY-WRAPPER ARGS...]
# (for example xvfb-run -a -s "-screen 0 1920x1200x24").
#
# QtTest's watchdog stops a test function that has not returned within
# QTEST_FUNCTION_TIMEOUT and prints every thread's stack. Under a loaded machine the GUI
# thread has been seen waiting for a reply from the virtual X server that never came (in
# libxcb's wait for a reply, the simulation thread still stepping): a stall of the display,
# not a result of the test. A run stopped that way is run once more; a failed check, a crash
# or a second stall fails the test.
set -u
program=$1
shift
log=$(mktemp) || exit 2
trap 'rm -f "$log"' EXIT
: "${QTEST_FUNCTION_TIMEOUT:=240000}"
export QTEST_FUNCTION_TIMEOUT
for attempt in 1 2; do
  "$@" "$program" > "$log" 2>&1
  status=$?
  cat "$log"
  if [ "$status" -eq 0 ] || ! grep -q "Test function timed out" "$log"; then
    exit "$status"
  fi
  [ "$attempt" -eq 1 ] && echo "run-gui-test: the run stalled (watchdog); running it once more"
done
exit "$status"
