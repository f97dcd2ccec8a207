"""Functional Mock-up Units (FMI 2.0 and 3.0) inside a model, through FMPy.

The spec's ``fmus:`` section names FMUs (exported from Simulink, OpenModelica, Dymola,
20-sim, ...) that compute part of the model: co-simulation FMUs advance by ``doStep``
beside the model's steps, model-exchange FMUs are integrated together with an ODE page.
FMPy is needed only by apps that use FMUs (``pip install 'ejsgen[fmu]'``).
"""

from __future__ import annotations

from ejsrl.fmi._instance import INSTALL_HINT, FmuError, FmuInstance, read_description, unpacked
from ejsrl.fmi.coupling import FmuDef, FmuRun, Fmus

__all__ = ["FmuDef", "Fmus", "FmuRun", "FmuError", "FmuInstance", "read_description", "unpacked", "INSTALL_HINT"]
