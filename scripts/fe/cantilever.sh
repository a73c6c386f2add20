#!/usr/bin/env bash
# Meshes the cantilever beam (gmsh) and runs CalculiX on it: the matrix export for a
# Craig–Bampton reduction and the reference eigenfrequencies.
#   scripts/fe/cantilever.sh OUT_DIR
# Writes in OUT_DIR: cantilever_mesh.inp (nodes, C3D20 elements, node sets Surface1..6),
# cantilever_matrices.{sti,mas,dof} and cantilever_frequency.dat. Needs `gmsh` and `ccx`
# (Debian packages gmsh and calculix-ccx).
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
out="${1:?usage: $0 OUT_DIR}"
mkdir -p "$out"
cp "$here/cantilever_material.inp" "$here/cantilever_matrices.inp" "$here/cantilever_frequency.inp" "$out/"
cd "$out"
gmsh -3 "$here/cantilever.geo" -format inp -setnumber Mesh.SaveGroupsOfNodes -2 \
    -o cantilever_mesh.inp > gmsh.log 2>&1 || { cat gmsh.log >&2; exit 1; }
for job in cantilever_matrices cantilever_frequency; do
    OMP_NUM_THREADS=1 ccx -i "$job" > "$job.log" 2>&1 || { cat "$job.log" >&2; exit 1; }
    if grep -q '\*ERROR' "$job.log"; then cat "$job.log" >&2; exit 1; fi
done
