#!/usr/bin/env bash
# Screenshot of the `raykit serve` web client in headless Chromium, for the
# README (docs/images/serve-client.png). Needs chromium, chromium-driver,
# curl and python3; builds the release binary.
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-docs/images/serve-client.png}
cargo build --release -q
./target/release/raykit serve --addr 127.0.0.1:18765 --seconds 60 &
server=$!
chromedriver --port=19515 >/dev/null 2>&1 &
driver=$!
trap 'kill $server $driver 2>/dev/null || true; pkill -f "remote-debugging-port=0" 2>/dev/null || true' EXIT
sleep 2
caps='{"capabilities":{"alwaysMatch":{"browserName":"chrome","goog:chromeOptions":{"args":["--headless","--no-sandbox","--disable-gpu","--window-size=960,600"]}}}}'
session=$(curl -s -X POST localhost:19515/session -H 'Content-Type: application/json' -d "$caps" |
  python3 -c 'import json,sys; print(json.load(sys.stdin)["value"]["sessionId"])')
api=localhost:19515/session/$session
curl -s -X POST "$api/url" -H 'Content-Type: application/json' -d '{"url":"http://127.0.0.1:18765/"}' >/dev/null
# Wait for the refined frame, then orbit a little so the overlay shows live figures.
for _ in $(seq 50); do
  done_=$(curl -s -X POST "$api/execute/sync" -H 'Content-Type: application/json' \
    -d '{"script":"return !!(window.raykit && window.raykit.lastHeader && window.raykit.lastHeader.stage===\"refined\")","args":[]}' |
    python3 -c 'import json,sys; print(json.load(sys.stdin)["value"])')
  [ "$done_" = True ] && break
  sleep 0.2
done
sleep 1.5
curl -s "$api/screenshot" | python3 -c 'import json,sys,base64; sys.stdout.buffer.write(base64.b64decode(json.load(sys.stdin)["value"]))' > "$out.tmp"
mv "$out.tmp" "$out"
curl -s -X DELETE "$api" >/dev/null
echo "wrote $out"
