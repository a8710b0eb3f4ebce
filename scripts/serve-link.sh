#!/usr/bin/env bash
# Remote rendering over a rate-limited link, measured as paper 001 measured
# its handheld over 802.11g (3.8 fps at 512², 15.2 fps at 256²):
# `raykit serve` runs in one network namespace, `raykit experiment serve
# --connect` in another, joined by a veth pair. Every size (512², 256²) ×
# payload (raw RGB, JPEG) is measured once without a rate limit and once
# with a token-bucket filter (tc tbf) on both veth ends.
#
# Rate: 24 Mbit/s. 802.11g signals at 54 Mbit/s, but its MAC overhead
# leaves about 20-25 Mbit/s of TCP throughput; and 24 Mbit/s is what the
# paper's own figures imply: 3.8 fps × 512·512·3 bytes × 8 = 23.9 Mbit/s and
# 15.2 fps × 256·256·3 bytes × 8 = 23.9 Mbit/s, i.e. raw 24-bit frames
# filling the link. Burst 32 KB (above rate/HZ, so tbf reaches its rate at
# any kernel tick rate); queue bounded by 50 ms. The kernel here has no
# sch_netem, so the link's latency and loss are not emulated: only its rate.
#
# Needs root (ip netns, tc). Regenerates docs/experiments/serve/link/
# (results.md, results.csv, fps.svg, runs/*/link.json) in one command:
#   sudo scripts/serve-link.sh [--raykit PATH] [--rate 24mbit] [--seconds 20] [--out DIR]
# Without --raykit it builds the release binary with cargo first.
set -euo pipefail

RAYKIT=""
RATE="24mbit"
BURST="32kb"
TBF_LATENCY="50ms"
SECONDS_PER_RUN=20
WARMUP=3
INPUT_HZ=60
SCENE="builtin:cornell"
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
OUT="$ROOT/docs/experiments/serve/link"

usage() { sed -n '2,22p' "$0" | sed 's/^# \{0,1\}//'; }
while [ $# -gt 0 ]; do
  case "$1" in
    --raykit) RAYKIT="$2"; shift 2 ;;
    --rate) RATE="$2"; shift 2 ;;
    --seconds) SECONDS_PER_RUN="$2"; shift 2 ;;
    --scene) SCENE="$2"; shift 2 ;;
    --out) OUT="$2"; shift 2 ;;
    -h|--help) usage; exit 0 ;;
    *) echo "serve-link.sh: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done
COMMAND="scripts/serve-link.sh --rate $RATE --seconds $SECONDS_PER_RUN --scene $SCENE"

if [ "$(id -u)" != 0 ]; then
  echo "serve-link.sh: needs root for ip netns and tc" >&2; exit 2
fi
for tool in ip tc python3; do
  command -v "$tool" >/dev/null || { echo "serve-link.sh: '$tool' not found" >&2; exit 2; }
done
if [ -z "$RAYKIT" ]; then
  (cd "$ROOT" && cargo build --release --bin raykit)
  RAYKIT="${CARGO_TARGET_DIR:-$ROOT/target}/release/raykit"
fi
RAYKIT="$(realpath "$RAYKIT")"
[ -x "$RAYKIT" ] || { echo "serve-link.sh: no executable at $RAYKIT" >&2; exit 2; }

# Names unique to this run, so runs side by side do not collide.
SNS="rkl-srv-$$"; CNS="rkl-cli-$$"
SVETH="rks$$"; CVETH="rkc$$"
SADDR=10.211.0.1; CADDR=10.211.0.2; PORT=8080
SERVER_PID=""
TMP="$(mktemp -d)"

cleanup() {
  set +e
  if [ -n "$SERVER_PID" ]; then kill "$SERVER_PID" 2>/dev/null; wait "$SERVER_PID" 2>/dev/null; fi
  # Deleting a namespace deletes the veth end in it, and with it the pair.
  ip netns del "$SNS" 2>/dev/null
  ip netns del "$CNS" 2>/dev/null
  rm -rf "$TMP"
}
trap cleanup EXIT INT TERM

ip netns add "$SNS"
ip netns add "$CNS"
ip link add "$SVETH" netns "$SNS" type veth peer name "$CVETH" netns "$CNS"
ip -n "$SNS" addr add "$SADDR/24" dev "$SVETH"
ip -n "$CNS" addr add "$CADDR/24" dev "$CVETH"
for ns in "$SNS" "$CNS"; do ip -n "$ns" link set lo up; done
ip -n "$SNS" link set "$SVETH" up
ip -n "$CNS" link set "$CVETH" up

ip netns exec "$SNS" "$RAYKIT" serve --scene "$SCENE" --addr "$SADDR:$PORT" \
  >"$TMP/server.log" 2>&1 &
SERVER_PID=$!
for _ in $(seq 1 100); do
  if ip netns exec "$CNS" bash -c "exec 3<>/dev/tcp/$SADDR/$PORT" 2>/dev/null; then break; fi
  kill -0 "$SERVER_PID" 2>/dev/null || { cat "$TMP/server.log" >&2; exit 1; }
  sleep 0.2
done

throttle() {
  for pair in "$SNS:$SVETH" "$CNS:$CVETH"; do
    ip -n "${pair%%:*}" link set "${pair#*:}" up
    tc -n "${pair%%:*}" qdisc replace dev "${pair#*:}" root tbf \
      rate "$RATE" burst "$BURST" latency "$TBF_LATENCY"
  done
}

# Bulk TCP throughput from the server's namespace to the client's (the
# frames' direction): 12 MB through one connection, timed by the receiver.
cat >"$TMP/bulk.py" <<'PY'
import socket, sys, time
role, host = sys.argv[1], sys.argv[2]
n = 12_000_000
if role == "send":
    s = socket.socket(); s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    s.bind((host, 5201)); s.listen(1); c, _ = s.accept()
    c.sendall(bytes(n)); c.close()
else:
    for _ in range(50):
        try:
            c = socket.create_connection((host, 5201)); break
        except OSError:
            time.sleep(0.1)
    t0, got = time.perf_counter(), 0
    while True:
        b = c.recv(1 << 20)
        if not b: break
        got += len(b)
    print(f"{got * 8 / (time.perf_counter() - t0) / 1e6:.1f}")
PY
bulk() {
  ip netns exec "$SNS" python3 "$TMP/bulk.py" send "$SADDR" & local sender=$!
  ip netns exec "$CNS" python3 "$TMP/bulk.py" recv "$SADDR"
  wait "$sender"
}

rm -rf "$OUT/runs"
mkdir -p "$OUT/runs"
LOAD_START="$(cut -d' ' -f1-3 /proc/loadavg)"
failed=0
for link in unthrottled "$RATE"; do
  [ "$link" = unthrottled ] || throttle
  echo "$link $(bulk)" >>"$TMP/bulk.txt"
  echo "== $link: bulk TCP $(tail -1 "$TMP/bulk.txt" | cut -d' ' -f2) Mbit/s"
  for size in 512 256; do
    for format in raw jpeg; do
      run="$link-$size-$format"
      load="$(cut -d' ' -f1 /proc/loadavg)"
      echo "== $run (load $load)"
      if ! ip netns exec "$CNS" "$RAYKIT" experiment serve \
          --connect "ws://$SADDR:$PORT/ws" --width "$size" --height "$size" \
          --format "$format" --seconds "$SECONDS_PER_RUN" --warmup "$WARMUP" \
          --input-hz "$INPUT_HZ" --out "$OUT/runs/$run"; then
        echo "serve-link.sh: run $run failed" >&2; failed=1
      fi
      echo "$run $link $size $format $load" >>"$TMP/runs.txt"
    done
  done
done
LOAD_END="$(cut -d' ' -f1-3 /proc/loadavg)"
QDISC="$(tc -n "$SNS" qdisc show dev "$SVETH" | head -1)"

python3 - "$OUT" "$TMP/runs.txt" "$TMP/bulk.txt" "$COMMAND" "$RATE" "$BURST" "$TBF_LATENCY" \
  "$LOAD_START" "$LOAD_END" "$QDISC" "$("$RAYKIT" --version 2>/dev/null || echo raykit)" \
  "$SECONDS_PER_RUN" "$WARMUP" "$INPUT_HZ" "$SCENE" <<'PY'
import csv, json, os, platform, sys
(out, runs_txt, bulk_txt, command, rate, burst, tbf_latency, load_start, load_end, qdisc,
 version, seconds, warmup, input_hz, scene) = sys.argv[1:]
paper = {512: 3.8, 256: 15.2}
cpu = next((l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo")
            if l.startswith("model name")), "unknown CPU")
cores = os.cpu_count()
bulk = dict(l.split() for l in open(bulk_txt))
rows = []
for line in open(runs_txt):
    run, link, size, fmt, load = line.split()
    path = os.path.join(out, "runs", run, "link.json")
    if not os.path.exists(path):
        continue
    l = json.load(open(path))["link"]
    rows.append({
        "link": link, "size": int(size), "format": fmt, "frames": l["frames"],
        "fps": round(l["fps"], 2), "kb_per_frame": round(l["message_bytes_per_frame"] / 1e3, 1),
        "mbit_per_s": round(l["mbit_per_second"], 2),
        "latency_p50_ms": l["latency_p50_ms"] and round(l["latency_p50_ms"], 1),
        "latency_p95_ms": l["latency_p95_ms"] and round(l["latency_p95_ms"], 1),
        "render_ms_median": l["render_ms_median"] and round(l["render_ms_median"], 1),
        "paper_fps": paper[int(size)], "errors": len(l["errors"]), "load1_at_start": float(load),
    })
with open(os.path.join(out, "results.csv"), "w", newline="") as f:
    w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
    w.writeheader()
    w.writerows(rows)
fmt_ms = lambda v: "–" if v is None else f"{v:.0f}"
md = [f"# raykit serve over a rate-limited link (paper 001's 802.11g remote rendering)", "",
      f"`{command}`", "",
      f"Machine: {cpu}, {cores} cores, {platform.system()} {platform.release()}; "
      f"load average {load_start} at the start, {load_end} at the end (shared machine).",
      f"Binary: {version}. Scene: {scene}. Each run: one client, {seconds} s orbiting at "
      f"{input_hz} inputs/s, the first {warmup} s not counted; every frame full size, 1 sample, "
      "acknowledged before the next is sent (one frame in flight).", "",
      f"Link: veth pair between two network namespaces; throttled runs add `tc tbf rate {rate} "
      f"burst {burst} latency {tbf_latency}` on both ends (`{qdisc}`). No latency or loss is "
      "emulated (the kernel has no sch_netem); unthrottled runs show what the renderer alone allows. "
      f"Bulk TCP throughput server → client (12 MB, one connection): unthrottled "
      f"{bulk.get('unthrottled', '–')} Mbit/s, throttled {bulk.get(rate, '–')} Mbit/s.", "",
      "| size | format | link | fps | paper fps (802.11g) | KB/frame | Mbit/s | latency p50 / p95 ms | render ms (median) | load |",
      "|---|---|---|---:|---:|---:|---:|---:|---:|---:|"]
for r in rows:
    md.append(f"| {r['size']}² | {r['format']} | {r['link']} | {r['fps']:.1f} | {r['paper_fps']} | "
              f"{r['kb_per_frame']:.1f} | {r['mbit_per_s']:.1f} | {fmt_ms(r['latency_p50_ms'])} / "
              f"{fmt_ms(r['latency_p95_ms'])} | {fmt_ms(r['render_ms_median'])} | {r['load1_at_start']} |")
md += ["", "KB/frame and Mbit/s count WebSocket message bytes (frame header + payload), "
       "not WebSocket/TCP/IP framing. Latency: client-side, from sending an orbit input to "
       "receiving the first frame that shows it.", ""]
open(os.path.join(out, "results.md"), "w").write("\n".join(md))
# Grouped bars: fps per size × format, unthrottled / throttled / paper.
groups = [(s, f) for s in (512, 256) for f in ("raw", "jpeg")]
series = [("unthrottled", "#4c78a8"), (rate, "#f58518"), ("paper (802.11g)", "#54a24b")]
def fps(s, f, link):
    if link.startswith("paper"):
        return paper[s]
    return next((r["fps"] for r in rows if (r["size"], r["format"], r["link"]) == (s, f, link)), 0.0)
top = max([fps(s, f, l) for s, f in groups for l, _ in series] + [1.0]) * 1.1
W, H, L, B, T = 640, 360, 50, 50, 40
gw = (W - L - 20) / len(groups); bw = gw / (len(series) + 1)
svg = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{H}" font-family="sans-serif" font-size="11">',
       f'<rect width="{W}" height="{H}" fill="white"/>',
       f'<text x="{W/2}" y="18" text-anchor="middle" font-size="13">raykit serve: frames per second over a {rate} link vs paper 001 (802.11g)</text>',
       f'<line x1="{L}" y1="{H-B}" x2="{W-20}" y2="{H-B}" stroke="black"/>',
       f'<line x1="{L}" y1="{T}" x2="{L}" y2="{H-B}" stroke="black"/>',
       f'<text x="14" y="{(T+H-B)/2}" transform="rotate(-90 14 {(T+H-B)/2})" text-anchor="middle">fps</text>']
for i in range(6):
    v = top * i / 5; y = H - B - (H - B - T) * i / 5
    svg.append(f'<text x="{L-4}" y="{y+4}" text-anchor="end">{v:.0f}</text>')
for g, (s, f) in enumerate(groups):
    x0 = L + g * gw + bw / 2
    for k, (link, colour) in enumerate(series):
        v = fps(s, f, link); h = (H - B - T) * v / top
        svg.append(f'<rect x="{x0 + k*bw:.1f}" y="{H-B-h:.1f}" width="{bw*0.9:.1f}" height="{h:.1f}" fill="{colour}"/>')
        svg.append(f'<text x="{x0 + k*bw + bw*0.45:.1f}" y="{H-B-h-3:.1f}" text-anchor="middle" font-size="9">{v:.1f}</text>')
    svg.append(f'<text x="{x0 + 1.5*bw:.1f}" y="{H-B+16}" text-anchor="middle">{s}² {f}</text>')
for k, (link, colour) in enumerate(series):
    svg.append(f'<rect x="{L + 10 + k*170}" y="{H-20}" width="10" height="10" fill="{colour}"/>')
    svg.append(f'<text x="{L + 24 + k*170}" y="{H-11}">{link}</text>')
svg.append("</svg>")
open(os.path.join(out, "fps.svg"), "w").write("\n".join(svg) + "\n")
print("\n".join(md))
PY
exit "$failed"
