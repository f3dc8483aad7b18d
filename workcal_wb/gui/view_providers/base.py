"""Base class of WorkCal's view provider proxies."""
import workcal_wb
from workcal_wb.fc.proxies import Proxy


class ViewProvider(Proxy):
    """View provider proxy whose tree icon is resources/icons/<ICON>.svg."""

    ICON = "WorkCal"

    def __init__(self, vobj):
        vobj.Proxy = self

    def attach(self, vobj):
        self.ViewObject = vobj
        self.Object = vobj.Object

    def getIcon(self):
        return workcal_wb.icon(self.ICON)
