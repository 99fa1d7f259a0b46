"""The physics core: parameters, closed forms, the exact joint, the slider bank, the protocol.

Imports only numpy, scipy, numba (the compiled Masing kernel, :mod:`.masing`) and the
package's conventions (:mod:`iwan_element.base`). Everything
public here is re-exported by :mod:`iwan_element`.
"""
