"""FreeCAD workbench for subd2nurbs: subdivision cages and triangle meshes to parametric NURBS
solids. Headless API: s2n_freecad.api (make_cage, make_nurbs, check_quality)."""
