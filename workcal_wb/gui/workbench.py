"""The WorkCal workbench; importing this module registers it with FreeCAD (see InitGui.py)."""
import FreeCAD
import FreeCADGui

import workcal_wb
from workcal_wb.gui import view_providers

QT_TRANSLATE_NOOP = FreeCAD.Qt.QT_TRANSLATE_NOOP

view_providers.register()  # objects the FreeCAD layer makes get their view providers (imported when attached)


class WorkCalWorkbench(FreeCADGui.Workbench):
    MenuText = QT_TRANSLATE_NOOP("Workbench", "WorkCal")
    ToolTip = QT_TRANSLATE_NOOP("Workbench", "Locate a freeform workpiece for a robot from one 3D scan "
                                             "and calibrate its toolpath")
    Icon = workcal_wb.icon("WorkCal")

    def Initialize(self):
        """Commands are imported only when the workbench is first activated, as FreeCAD recommends."""
        from workcal_wb.gui import commands

        commands.register_all()
        self.appendToolbar("WorkCal", commands.TOOLBAR)
        self.appendMenu("&WorkCal", commands.MENU)
        FreeCADGui.addIconPath(workcal_wb.ICONS)
        FreeCADGui.addLanguagePath(workcal_wb.TRANSLATIONS)
        FreeCADGui.updateLocale()

    def GetClassName(self):
        return "Gui::PythonWorkbench"


FreeCADGui.addWorkbench(WorkCalWorkbench())
