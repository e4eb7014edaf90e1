#!/usr/bin/env bash
# Hashes the JSON of the bundled examples, timing fields removed, so that two builds of the
# binary can be compared: `scripts/dev/golden.sh BIN OUTDIR`, then `diff -r OUT1 OUT2`.
set -uo pipefail
bin=$(realpath "$1"); out=$2
cd "${LINKSPACE_REPO:-$(dirname "$0")/../..}"
mkdir -p "$out"
run() { # name, args...
  local name=$1; shift
  if "$bin" "$@" --json "$out/$name.raw.json" > "$out/$name.txt" 2>"$out/$name.err"; then :; else echo "exit $?" >> "$out/$name.txt"; fi
  if [ -f "$out/$name.raw.json" ]; then
    jq -S 'walk(if type == "object" then with_entries(select(.key | test("seconds|^time|cpu|_s$|phases") | not)) else . end)' "$out/$name.raw.json" > "$out/$name.json"
    rm "$out/$name.raw.json"
  fi
  # the text summary without timings
  sed -i -E 's/[0-9]+\.[0-9]+ s\b/T s/g' "$out/$name.txt"
  sed -i -E "s/\((cover|cusps) [^)]*\)/(T)/" "$out/$name.txt"
}
run solve_four_bar solve urdf/four_bar.urdf --fix crank_joint=0.5 --sigma 1e-4
run solve_butterfly_rigid solve urdf/double_butterfly.urdf --fix joint6=1.1760052070951352 --sigma 1e-4
run solve_butterfly_mobile solve urdf/double_butterfly.urdf --sigma 0.05
run solve_rssr solve urdf/rssr.urdf --sigma 1e-3
run solve_bennett solve urdf/bennett.urdf --sigma 1e-2
for r in a b d e f; do run sing_$r singularities urdf/orthogonal_3r_$r.urdf --nodes; done
for r in puma560 kuka_kr16 ur5; do run sing_$r singularities urdf/$r.urdf; done
run sing_iiwa singularities urdf/iiwa14.urdf --lock joint_3=0.5 --ignore-limits
run ik_e ik urdf/orthogonal_3r_e.urdf --point 2,1
run ik_a ik urdf/orthogonal_3r_a.urdf --point 3,1
run ik_puma ik urdf/puma560.urdf --point 0.5,0.3
run coll_column collisions urdf/orthogonal_3r_a_column.urdf
run dist_oct distances urdf/octahedral.urdf --fix leg15=4.25 --fix leg16=5.75 --fix leg26=4.25 --fix leg24=5.75 --fix leg34=4.25 --fix leg35=5.75
run dist_spheres distances urdf/four_spheres.json
run loops_five_bar loop-singularities urdf/five_bar.urdf
run loops_four_bar loop-singularities urdf/four_bar.urdf
run ik_e_xyz ik urdf/orthogonal_3r_e.urdf --point 1.5,0.5,1
run loops_five_bar_image loop-singularities urdf/five_bar_unequal.urdf --actuated crank1_joint,crank2_joint --kind image --sigma 1e-2 --grid 64
