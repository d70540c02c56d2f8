#!/usr/bin/env bash
# Screenshot a Rerun recording as a user sees it: the Rerun web viewer in
# headless Chromium (SwiftShader WebGL), captured through the DevTools protocol.
#
#   scripts/rerun_screenshot.sh logs/disk_paper/run.rrd out.png [wait_s]
#
# Needs: rerun-sdk==0.36.3 (pip, for the `rerun` CLI with its web viewer),
# chromium (apt), websocket-client (pip). The native viewer draws nothing
# under Xvfb on these machines (Vulkan/llvmpipe), hence the web viewer.
set -euo pipefail
rrd=$1
out=$2
wait_s=${3:-75}
here=$(cd "$(dirname "$0")" && pwd)
command -v rerun >/dev/null || { echo "error: rerun not found (pip install rerun-sdk==0.36.3)" >&2; exit 2; }
rerun analytics disable >/dev/null 2>&1 || true
port() { python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1",0)); print(s.getsockname()[1])'; }
web=$(port)
grpc=$(port)
# Own session: `rerun` is a wrapper whose viewer child would outlive a plain
# kill of $pid (and keep a core busy).
setsid rerun --serve-web --web-viewer-port "$web" --port "$grpc" "$rrd" >/tmp/rerun-serve-$web.log 2>&1 &
pid=$!
trap 'kill -- -$pid 2>/dev/null || kill $pid 2>/dev/null || true' EXIT
for _ in $(seq 1 100); do
  curl -fs "http://127.0.0.1:$web/" >/dev/null 2>&1 && break
  sleep 0.3
done
python3 "$here/cdp_screenshot.py" \
  "http://127.0.0.1:$web/?url=rerun%2Bhttp%3A%2F%2Flocalhost%3A$grpc%2Fproxy&renderer=webgl" \
  "$out" --wait "$wait_s" --width 1600 --height 1000
