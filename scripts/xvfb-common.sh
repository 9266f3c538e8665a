# Shared by the scripts that drive the real window under Xvfb (sourced, not run).
#
# start_xvfb NAME FIRST LAST OUT: picks a free display number in FIRST..LAST, starts Xvfb on it
# (1280×800, log in OUT/xvfb.log), exports DISPLAY, and waits until it answers. An EXIT trap
# stops the app (whose pid the caller puts in app_pid) and Xvfb, whatever happens.

app_pid=""
xvfb_pid=""

stop_xvfb_and_app() {
  [ -n "$app_pid" ] && kill "$app_pid" 2>/dev/null || true
  [ -n "$xvfb_pid" ] && kill "$xvfb_pid" 2>/dev/null || true
  wait 2>/dev/null || true
}

start_xvfb() {
  local name=$1 first=$2 last=$3 out=$4 display="" n
  for n in $(seq "$first" "$last"); do
    if [ ! -e "/tmp/.X$n-lock" ] && [ ! -e "/tmp/.X11-unix/X$n" ]; then
      display=":$n"
      break
    fi
  done
  [ -n "$display" ] || { echo "$name: no free X display number" >&2; exit 1; }
  trap stop_xvfb_and_app EXIT
  Xvfb "$display" -screen 0 1280x800x24 -nolisten tcp >"$out/xvfb.log" 2>&1 &
  xvfb_pid=$!
  export DISPLAY="$display"
  for _ in $(seq 100); do
    xdotool getdisplaygeometry >/dev/null 2>&1 && break
    sleep 0.1
  done
  xdotool getdisplaygeometry >/dev/null || { echo "$name: Xvfb did not start" >&2; exit 1; }
}
