"""The physics core: parameters, closed forms, the exact joint, the slider bank, the protocol.

Imports only numpy, scipy and numba (the compiled Masing kernel, :mod:`.masing`). Everything
public here is re-exported by :mod:`iwan_element`.
"""
