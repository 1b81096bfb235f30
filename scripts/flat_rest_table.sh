#!/usr/bin/env bash
# The flat-rest corpus table of docs/pattern.md: every example and design of data/ draped as
# written plus "rest": "flat" (images off, one thread, the file's duration), one row per sketch:
# at rest (s), the fastest speed and kinetic energy per kg at the end, penetrating vertices, the
# largest strain max and mean over the panels, and the run's CPU seconds (user + system).
# Usage: scripts/flat_rest_table.sh BINARY OUT_DIR [sketch.json ...]  (default: all of data/)
set -u
bin=$1; out=$2; shift 2
root=$(cd "$(dirname "$0")/.." && pwd)
files=("$@")
[ ${#files[@]} -eq 0 ] && files=("$root"/data/examples/*.json "$root"/data/designs/*.json)
mkdir -p "$out"
printf '| sketch | at rest (s) | speed at the end m/s | KE J/kg | penetrating | strain max / mean of panels | CPU s |\n|---|---|---|---|---|---|---|\n'
for f in "${files[@]}"; do
  name=$(basename "$f" .json)
  dir="$out/$name"; mkdir -p "$dir"
  python3 - "$f" "$dir/$name.json" <<'PY'
import json, re, sys
text = open(sys.argv[1]).read()
# strip // comments outside strings
out, i, s = [], 0, False
while i < len(text):
    c = text[i]
    if s:
        out.append(c)
        if c == '\\': out.append(text[i+1]); i += 1
        elif c == '"': s = False
    elif c == '"': s = True; out.append(c)
    elif text.startswith('//', i):
        while i < len(text) and text[i] != '\n': i += 1
        continue
    else: out.append(c)
    i += 1
j = json.loads(''.join(out))
import os
base = os.path.dirname(os.path.abspath(sys.argv[1]))
body = j.get('body')
def fix(p):
    return p if (not isinstance(p, str) or p == 'builtin' or os.path.isabs(p)) else os.path.join(base, p)
if isinstance(body, dict) and 'mesh' in body: body['mesh'] = fix(body['mesh'])
elif isinstance(body, str): j['body'] = fix(body)
j.setdefault('simulate', {})['rest'] = 'flat'
j['output'] = {'images': []}
json.dump(j, open(sys.argv[2], 'w'), indent=1)
PY
  # relative fabric files etc.: run from the sketch's folder
  ( cd "$(dirname "$f")" && OMP_THREAD_LIMIT=1 OPENBLAS_NUM_THREADS=1 /usr/bin/time -f "%U %S" -o "$dir/time" \
      "$bin" run "$dir/$name.json" -o "$dir/run" >"$dir/log" 2>&1 )
  python3 - "$dir" "$name" <<'PY'
import json, sys
d, name = sys.argv[1], sys.argv[2]
u, s = map(float, open(d + '/time').read().strip().splitlines()[-1].split()[:2])
try:
    r = json.load(open(d + '/run/report.json'))
except Exception:
    log = [l for l in open(d + '/log').read().splitlines() if l.startswith('error:')]
    print(f"| {name} | failed: {log[-1][7:120] if log else ''} | | | | | {u+s:.1f} |"); sys.exit()
sim = r
rest = sim['rest']
at = f"yes ({sim['sim_time']:.2f})" if sim['at_rest'] else f"**no** ({sim['sim_time']:.2f} s)"
smax = max(g['strain_max'] for g in r['strain']); smean = sum(g['strain_mean'] for g in r['strain']) / len(r['strain'])
print(f"| {name} | {at} | {rest['speed_final_m_s']:.3f} | {rest['kinetic_per_kg_final_J_kg']:.2e} | {sim['penetrating_vertices_final']} | {100*smax:.1f} % / {100*smean:.2f} % | {u+s:.1f} |")
PY
done
