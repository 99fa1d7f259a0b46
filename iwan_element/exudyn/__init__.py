"""The Exudyn adapter: the only part of the package that imports exudyn.

:func:`add_iwan_connector` puts any joint element between two Exudyn markers; see
:mod:`iwan_element.exudyn.connector`.
"""
from .connector import IwanConnector, add_iwan_connector
from .interface import IwanInterface, add_iwan_interface

__all__ = ["add_iwan_connector", "IwanConnector", "add_iwan_interface", "IwanInterface"]
