#!/bin/bash
# Measures `hostctl ui` at 5 kHz telemetry with a page open in headless Chromium (docs/UI.md):
# 1. CPU of `hostctl stream --rate 5000` (the same virtual device without the UI), 60 s;
# 2. CPU of `hostctl ui --rate 5000` and of Chromium with the page open, 60 s, and the page's
#    redraw rate;
# 3. a soak of SOAK_S seconds (default 600) with the page open while recording from the page,
#    a release test every minute: RSS every 30 s; the recording checked for gaps afterwards.
# Needs: cargo build --release -p stiffwall-host; Debian's chromium and chromium-driver (as
# installed by `cargo xtask ci`); curl, python3, bc. Run from the repository root.
set -eu
BIN=${BIN:-target/release/hostctl}
SOAK_S=${SOAK_S:-600}
OUT=$(mktemp -d)
DPORT=${DPORT:-9616}
HZ=$(getconf CLK_TCK)
cpu() { local s=0; for p in "$@"; do s=$((s + $(awk '{print $14+$15}' /proc/$p/stat 2>/dev/null || echo 0))); done; echo $s; }
pct() { echo "scale=1; ($2-$1)*100/$HZ/$3" | bc; }
rss() { awk '/VmRSS/{print $2}' /proc/$1/status; }

$BIN stream --rate 5000 > $OUT/stream.out 2>&1 &
SP=$!; sleep 5; c0=$(cpu $SP); sleep 60; c1=$(cpu $SP); kill -INT $SP; wait $SP || true
echo "hostctl stream --rate 5000: $(pct $c0 $c1 60) % of one core"

$BIN ui --rate 5000 --listen 127.0.0.1:0 --record-dir $OUT > $OUT/ui.out 2>&1 &
UP=$!; sleep 3
URL=$(grep -o 'http://[^ ]*' $OUT/ui.out); API="${URL/\/?token=//api/cmd?token=}"
chromedriver --port=$DPORT > /dev/null 2>&1 &
DP=$!; sleep 2
WD=http://127.0.0.1:$DPORT
SID=$(curl -s -X POST $WD/session -d '{"capabilities":{"alwaysMatch":{"goog:chromeOptions":{"binary":"/usr/bin/chromium","args":["--headless=new","--no-sandbox","--disable-gpu","--disable-dev-shm-usage","--window-size=1600,1300","--disable-crash-reporter","--disable-breakpad"]}}}}' | python3 -c 'import json,sys; print(json.load(sys.stdin)["value"]["sessionId"])')
curl -s -X POST $WD/session/$SID/url -d "{\"url\":\"$URL\"}" > /dev/null
js() { curl -s -X POST $WD/session/$SID/execute/sync -d "{\"script\":\"return document.getElementById('$1').dataset.$2\",\"args\":[]}" | python3 -c 'import json,sys; print(json.load(sys.stdin)["value"])'; }
api() { curl -s -X POST "$API" -d "$1"; }
api '{"cmd":"config","set":{"stiffness":0.8}}' > /dev/null
sleep 5
CH=$(pgrep -f /usr/lib/chromium/chromium | tr '\n' ' ')
c0=$(cpu $UP); b0=$(cpu $CH); sleep 60; c1=$(cpu $UP); b1=$(cpu $CH)
echo "hostctl ui --rate 5000, page open: $(pct $c0 $c1 60) % of one core; Chromium (all processes, software rendering): $(pct $b0 $b1 60) %; page redraws $(js fps fps)/s"

api '{"cmd":"record_start","file":"soak.csv"}' > /dev/null
T0=$(date +%s); c1=$(cpu $UP)
for i in $(seq 0 $((SOAK_S / 30))); do
  echo "t = $(( $(date +%s) - T0 )) s: RSS $(rss $UP) kB, page samples $(js sample-count count), redraws $(js fps fps)/s"
  if [ $((i % 2)) = 1 ]; then
    api '{"cmd":"release","args":{"deflection":20,"ticks":2000}}' | python3 -c 'import json,sys; d=json.load(sys.stdin); print("  release test:", d["result"]["describe"] if d["ok"] else d["error"])'
  fi
  [ $i = $((SOAK_S / 30)) ] || sleep 30
done
echo "stopped: $(api '{"cmd":"record_stop"}')"
c2=$(cpu $UP)
echo "hostctl ui during the soak: $(pct $c1 $c2 $(( $(date +%s) - T0 ))) % of one core"
curl -s -X DELETE $WD/session/$SID > /dev/null
kill $DP; kill -INT $UP; wait $UP || true
echo "gap notes in the recording: $(grep -c '^# gap' $OUT/soak.csv || true)"
grep '^# end' $OUT/soak.csv
python3 - "$OUT/soak.csv" <<'PY'
import sys
seqs = [int(l.split(',', 1)[0]) for l in open(sys.argv[1]) if l[:1].isdigit()]
bad = sum(1 for a, b in zip(seqs, seqs[1:]) if b != a + 1)
print(f"rows {len(seqs)}, sample numbers {seqs[0]}..{seqs[-1]}, non-consecutive steps {bad}")
PY
rm -rf "$OUT"
