"""The physics core: parameters, closed forms, the exact joint, the slider bank, the protocol.

Imports only numpy and scipy. Everything public here is re-exported by :mod:`iwan_element`.
"""
