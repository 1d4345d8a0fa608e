# Subd2Nurbs workbench, GUI start-up (executed by FreeCAD, not imported).
import os


class Subd2NurbsWorkbench(Workbench):  # noqa: F821 (Workbench is provided by FreeCAD)
    MenuText = "Subd2Nurbs"
    ToolTip = "Subdivision cages and triangle meshes to parametric NURBS solids"

    def __init__(self):
        import s2n_freecad.features
        self.__class__.Icon = os.path.join(s2n_freecad.features.ICONS, "Subd2Nurbs.svg")

    def Initialize(self):
        import s2n_freecad.commands
        names = list(s2n_freecad.commands.COMMANDS)
        self.appendToolbar("Subd2Nurbs", names)
        self.appendMenu("Subd2Nurbs", names)

    def Activated(self):
        pass

    def Deactivated(self):
        pass

    def GetClassName(self):
        return "Gui::PythonWorkbench"


Gui.addWorkbench(Subd2NurbsWorkbench())  # noqa: F821
