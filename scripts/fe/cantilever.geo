// Cantilever beam for the Craig–Bampton validation (tests/fe_reduction.rs): a steel bar of
// square section along x, clamped at x = 0, meshed with 20-node hexahedra (C3D20 in CalculiX).
// Lengths in m. Mesh: 2 × 2 elements across the section, 40 along the length.
// Run by scripts/fe/cantilever.sh: gmsh -3 cantilever.geo -format inp -setnumber Mesh.SaveGroupsOfNodes -2
// writes the mesh and one node set per surface: Surface1 is the face x = 0 (clamped),
// Surface2 the face x = L (the tip, the interface of the reduction).
SetFactory("OpenCASCADE");
L = 0.4;      // length
W = 0.01;     // width (y)
H = 0.01;     // height (z)
Box(1) = {0, 0, 0, L, W, H};
// Structured mesh: curves along y and z get 3 nodes (2 elements), along x 41 (40 elements).
Transfinite Curve{1:8} = 3;
Transfinite Curve{9:12} = 41;
Transfinite Surface{:};
Transfinite Volume{:};
Recombine Surface{:};
Mesh.ElementOrder = 2;
Mesh.SecondOrderIncomplete = 1;  // 20-node serendipity hexahedra
// Only the volume's elements are written (no surface elements); the node sets come from
// Mesh.SaveGroupsOfNodes = -2 (one set per surface entity).
Physical Volume("beam") = {1};
