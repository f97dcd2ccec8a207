"""ejsrl.plant: the reference plant of a remote laboratory (issue #26; the paper's RobUALab).

A stand-in for real hardware: a 5-axis educational arm with motor dynamics, friction and sensor
noise (:mod:`._arm`), guarded by a class-wide lease with a queue, a heartbeat watchdog and an
emergency stop (:mod:`._core`), served over MQTT (paho-mqtt against a broker such as mosquitto)
and OPC UA (asyncua). Run it with ``python -m ejsrl.plant --mqtt 127.0.0.1:1883``.
"""

from __future__ import annotations

from ._arm import Arm, ArmParams
from ._core import Plant, PlantConfig
from ._creds import Credentials, load_credentials

__all__ = ["Arm", "ArmParams", "Plant", "PlantConfig", "Credentials", "load_credentials"]
