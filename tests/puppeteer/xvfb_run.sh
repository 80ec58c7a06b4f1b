# SPDX-License-Identifier: MIT
# Sourced by the app tests. xvfb_run XVFB_RUN COMMAND [ARGS...]: runs COMMAND under a fresh Xvfb (xvfb-run -a) and
# returns COMMAND's own exit status, or 127 if Xvfb never ran it. xvfb-run's own status is not COMMAND's when it
# fails to remove its temporary directory afterwards ("problem while cleaning up temporary directory", status 5),
# which it now and then does when several run at once (ctest -j); COMMAND's output passes through untouched.
xvfb_run() {
  local xvfb=$1 status_file status
  shift
  status_file=$(mktemp)
  "$xvfb" -a bash -c '"$@"; echo $? >"$0"' "$status_file" "$@" || true
  status=$(cat "$status_file")
  rm -f "$status_file"
  return "${status:-127}"
}
