"""SUMO co-simulation: city-scale background traffic driven by SUMO (libsumo, in process) on skytrack's own roads.

Needs the ``traffic`` extra (eclipse-sumo, libsumo); nothing here imports SUMO until a source is made.
"""

from vehicles.sumo._runtime import INSTALL_HINT, SumoUnavailable, sumo_available
from vehicles.sumo.demand import DemandConfig
from vehicles.sumo.network import NetConfig, SumoNet, build_sumo_net
from vehicles.sumo.source import SumoTraffic, SumoTrafficConfig, make_sumo_traffic

__all__ = ["INSTALL_HINT", "DemandConfig", "NetConfig", "SumoNet", "SumoTraffic", "SumoTrafficConfig",
           "SumoUnavailable", "build_sumo_net", "make_sumo_traffic", "sumo_available"]
