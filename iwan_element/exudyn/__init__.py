"""The Exudyn adapter: the only part of the package that imports exudyn.

:func:`create_iwan_connector` puts Iwan joints between two bodies, nodes or markers in
Exudyn's own idiom (as ``mbs.CreateCartesianSpringDamper``; see
:mod:`iwan_element.exudyn.cartesian`); :func:`add_iwan_connector` puts any joint element
between two Exudyn markers (see :mod:`iwan_element.exudyn.connector`);
:func:`add_iwan_interface` puts one exact Iwan joint at each of many contact points,
committed together once per step (see :mod:`iwan_element.exudyn.interface`; its handle
:mod:`.interface_handle`); :func:`record_energy` books the energy balance of a model holding
them (:mod:`iwan_element.exudyn.energy`; the balance as a result: :mod:`.energy_balance`).
The post-step dispatcher they share is :mod:`._dispatch`.

Inside (bottom to top): :mod:`.slips` (the accepted slips read from Exudyn's coordinates
after each step, and their records), :mod:`.laws` (the force laws Exudyn evaluates:
symbolic, Python, the interface's springs), then this folder's public adapters.
"""

from .cartesian import IwanCartesianConnector, create_iwan_connector
from .connector import IwanConnector, add_iwan_connector
from .energy import EnergyRecorder, record_energy
from .energy_balance import EnergyBalance
from .interface import add_iwan_interface
from .interface_handle import IwanInterface

__all__ = [
    "create_iwan_connector",
    "IwanCartesianConnector",
    "add_iwan_connector",
    "IwanConnector",
    "add_iwan_interface",
    "IwanInterface",
    "record_energy",
    "EnergyRecorder",
    "EnergyBalance",
]
