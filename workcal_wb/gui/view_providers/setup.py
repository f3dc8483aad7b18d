"""The document's WorkCal setup: double-click opens the guide at the models step."""
from workcal_wb.gui.view_providers.base import ViewProvider


class ViewProviderSetup(ViewProvider):
    ICON = "WorkCal_Setup"

    def doubleClicked(self, vobj):
        from workcal_wb.gui.commands.guide import open_guide

        open_guide(vobj.Object.Document, "models")
        return True
