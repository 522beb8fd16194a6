#!/usr/bin/env bash
# Check that generated course files load in GNU Octave exactly like the course files, and that
# the course method written MATLAB-style (H\y) on them gives what `tiltbench calibrate` gives.
# Needs octave-cli (Debian: apt install --no-install-recommends octave). Usage: make octave-check
set -euo pipefail
BIN=${BIN:-.venv/bin}
OUT=$(mktemp -d)
trap 'rm -rf "$OUT"' EXIT
"$BIN/tiltbench" generate course --seed 7 --out "$OUT/set" > /dev/null
"$BIN/tiltbench" calibrate "$OUT/set/ensayo.mat" --datos "$OUT/set/datos.txt" --json > "$OUT/est.json"
read -r BX SX BY SY < <("$BIN/python" -c "
import json; a = json.load(open('$OUT/est.json'))['axes']
print(a['x']['bias'], a['x']['scale'], a['y']['bias'], a['y']['scale'])")
octave-cli --no-gui --quiet --eval "
c = load('../shared/course-data/ensayo.mat'); g = load('$OUT/set/ensayo.mat');
assert(isequal(sort(fieldnames(c)), sort(fieldnames(g))));
assert(size(g.tita, 2) == 1 && size(g.datos, 2) == 2 && isa(g.datos, 'double'));
ca = load('../shared/course-data/acel.mat'); ga = load('$OUT/set/acel.mat');
assert(isequal(sort(fieldnames(ca)), sort(fieldnames(ga))));
cp = load('../shared/course-data/puntos.mat'); gp = load('$OUT/set/puntos.mat');
assert(isequal(sort(fieldnames(cp)), sort(fieldnames(gp))) && isequal(size(gp.A), [1 2]));
N = size(g.tita, 1);
Hx = [ones(N, 1), -9.8*sin(g.tita)]; px = Hx \\ (g.datos(:, 1) + 9.8*sin(g.tita));
Hy = [ones(N, 1), -9.8*cos(g.tita)]; py = Hy \\ (g.datos(:, 2) + 9.8*cos(g.tita));
ref = [$BX $SX $BY $SY]; got = [px' py'];
assert(max(abs(got - ref) ./ max(abs(ref), 1e-3)) < 1e-9, 'octave LS differs from tiltbench');
printf('octave %s: files load like the course files; H\\\\y matches tiltbench calibrate\n', version());
"
