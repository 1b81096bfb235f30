#!/usr/bin/env python3
"""Drapes one sketch at neighbouring settings, to tell a drape that rests from one that rests by luck.

Usage: scripts/neighbour_sweep.py BINARY OUT_DIR SKETCH.json [--flat] [--duration S]
           [--set KEY=VALUE ...] [--grid offset=0.0145,0.0155 --grid edge_length=0.024,0.025 ...]

Every combination of the --grid values (top-level keys of the sketch, or simulate.KEY) is run
with images off and one thread (`run --threads 1`), one at a time; a line per run: the values,
at rest (and when), steps, the fastest speed at the end, penetrating vertices, piercing body
vertices, CPU seconds (user + system, /usr/bin/time). The last line counts the runs at rest.
"""
import itertools, json, os, subprocess, sys
from sketch_json import strip_comments  # scripts/sketch_json.py, beside this file


def put(sketch, key, value):
    target = sketch
    parts = key.split('.')
    for p in parts[:-1]:
        target = target.setdefault(p, {})
    target[parts[-1]] = value


def main(argv):
    binary, out, path = os.path.abspath(argv[0]), os.path.abspath(argv[1]), os.path.abspath(argv[2])
    flat, duration, sets, grid = False, None, [], []
    rest = argv[3:]
    i = 0
    while i < len(rest):
        if rest[i] == '--flat':
            flat = True
        elif rest[i] == '--duration':
            duration = float(rest[i + 1]); i += 1
        elif rest[i] == '--set':
            k, v = rest[i + 1].split('=', 1); sets.append((k, json.loads(v))); i += 1
        elif rest[i] == '--grid':
            k, v = rest[i + 1].split('=', 1)
            grid.append((k, [json.loads(x) for x in v.split(',')])); i += 1
        else:
            sys.exit(f'unknown argument {rest[i]}')
        i += 1
    base = json.loads(strip_comments(open(path).read()))
    os.makedirs(out, exist_ok=True)
    name = os.path.splitext(os.path.basename(path))[0]
    rested = runs = 0
    for values in itertools.product(*[v for _, v in grid]):
        sketch = json.loads(json.dumps(base))
        if flat:
            put(sketch, 'simulate.rest', 'flat')
        if duration is not None:
            put(sketch, 'simulate.duration', duration)
        for k, v in sets:
            put(sketch, k, v)
        label = '_'.join(f'{k.split(".")[-1]}{v}' for (k, _), v in zip(grid, values)) or 'as-written'
        for (k, _), v in zip(grid, values):
            put(sketch, k, v)
        sketch['output'] = {'images': []}
        run_dir = os.path.join(out, f'{name}-{label}')
        os.makedirs(run_dir, exist_ok=True)
        sketch_path = os.path.join(run_dir, 'sketch.json')
        json.dump(sketch, open(sketch_path, 'w'), indent=1)
        env = dict(os.environ, OMP_THREAD_LIMIT='1', OPENBLAS_NUM_THREADS='1')
        with open(os.path.join(run_dir, 'log'), 'w') as log:
            subprocess.run(['/usr/bin/time', '-f', '%U %S', '-o', os.path.join(run_dir, 'time'),
                            binary, 'run', sketch_path, '-o', os.path.join(run_dir, 'run'),
                            '--threads', '1'], cwd=os.path.dirname(path), stdout=log,
                           stderr=subprocess.STDOUT, env=env)
        user, system = map(float, open(os.path.join(run_dir, 'time')).read().split()[-2:])
        runs += 1
        try:
            r = json.load(open(os.path.join(run_dir, 'run', 'report.json')))
        except Exception:
            errors = [l for l in open(os.path.join(run_dir, 'log')) if l.startswith('error')]
            print(f'{label}\tfailed: {errors[-1].strip()[:100] if errors else "?"}\t{user + system:.1f}',
                  flush=True)
            continue
        at_rest = r.get('at_rest', False)
        rested += bool(at_rest)
        rest_info = r.get('rest', {})
        print(f"{label}\t{'rest' if at_rest else 'MOVING'} {r.get('sim_time', 0):.2f} s\t"
              f"steps {r.get('steps', '?')}\tspeed {rest_info.get('speed_final_m_s', float('nan')):.3g}\t"
              f"pen {r.get('penetrating_vertices_final', '?')}\tpierce {r.get('piercing_body_vertices_final', '?')}\t"
              f"cpu {user + system:.1f}", flush=True)
    print(f'at rest: {rested} of {runs}', flush=True)


if __name__ == '__main__':
    main(sys.argv[1:])
