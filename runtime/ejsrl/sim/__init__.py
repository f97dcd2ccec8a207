"""ejsrl.sim: the model base class, evolution pages, ODE solvers and events."""

from ejsrl.sim._layout import StateLayout
from ejsrl.sim.model import CodePage, Controller, ModelBase, OdePage, UserCodeError
from ejsrl.sim.ode import METHODS, EventDef, OdeIntegrator, ZenoError
from ejsrl.sim.world_access import WorldAccess, WorldFunctionsAccess

__all__ = [
    "ModelBase",
    "CodePage",
    "OdePage",
    "Controller",
    "UserCodeError",
    "StateLayout",
    "EventDef",
    "OdeIntegrator",
    "ZenoError",
    "METHODS",
    "WorldAccess",
    "WorldFunctionsAccess",
]
