# Progress for the long steps of scripts/run_main.sh, test.sh and sanitize.sh (sourced, not run):
# a user waiting on a step sees a line at its start and then at least every 10 s.
#
#   watch_step build LABEL LOG CMD...   CMD's output goes to LOG; every 10 s one line with the
#                                       build's percentage and the file being compiled
#   watch_step stream LABEL LOG CMD...  CMD's output is shown as it comes (and kept in LOG); after
#                                       15 s without output, a line saying it is still running
# Returns CMD's exit status; on failure a build step shows the end of its log.

elapsed_text() {  # seconds -> "42 s" / "3 min 05 s"
  local s=$1
  if [ "$s" -lt 60 ]; then echo "$s s"; else printf '%d min %02d s\n' $((s / 60)) $((s % 60)); fi
}

# The build's last "[ 45%] Building CXX object .../stage_loop.cpp.o" line as "45 %, stage_loop.cpp".
build_status() {
  local line
  line=$(grep -a -o '^\[ *[0-9]*%\].*' "$1" 2>/dev/null | tail -n 1) || true
  [ -n "$line" ] || { echo "running"; return; }
  local pct=${line%%%]*}; pct=${pct#[}; pct=${pct// /}
  local what=${line##* }; what=${what##*/}; what=${what%.o}
  echo "$pct %, $what"
}

watch_step() {
  local mode=$1 label=$2 log=$3; shift 3
  local start=$SECONDS last=$SECONDS offset size rc=0
  touch "$log"
  offset=$(stat -c %s "$log")
  echo "[$label] $* (log: $log)"
  "$@" >> "$log" 2>&1 &
  local pid=$!
  while kill -0 "$pid" 2> /dev/null; do
    sleep 1
    if [ "$mode" = stream ]; then
      size=$(stat -c %s "$log")
      if [ "$size" -gt "$offset" ]; then
        tail -c +$((offset + 1)) "$log" | head -c $((size - offset))
        offset=$size
        last=$SECONDS
      elif [ $((SECONDS - last)) -ge 15 ]; then
        echo "[$label] still running ($(elapsed_text $((SECONDS - start))))"
        last=$SECONDS
      fi
    elif [ $((SECONDS - last)) -ge 10 ]; then
      echo "[$label] $(build_status "$log") ($(elapsed_text $((SECONDS - start))))"
      last=$SECONDS
    fi
  done
  wait "$pid" || rc=$?
  if [ "$mode" = stream ]; then
    size=$(stat -c %s "$log")
    [ "$size" -gt "$offset" ] && tail -c +$((offset + 1)) "$log"
  elif [ "$rc" -ne 0 ]; then
    tail -n 50 "$log"
  fi
  echo "[$label] $([ "$rc" -eq 0 ] && echo done || echo "FAILED (exit $rc)") in $(elapsed_text $((SECONDS - start)))"
  return "$rc"
}
