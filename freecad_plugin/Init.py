# Subd2Nurbs workbench, non-GUI start-up: nothing to register (the API is imported on demand:
# import s2n_freecad.api). FreeCAD puts this Mod folder on sys.path, which makes both
# s2n_freecad and the subd2nurbs module installed next to it importable.
