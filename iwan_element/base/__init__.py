"""The package's conventions that every room uses: the one result shape
(:mod:`.result_shape`), JSON-safe values (:mod:`.serialize`), argument checks
(:mod:`.validation`), progress reporting (:mod:`.progress`), the BLAS thread limit
(:mod:`.threads`) and the rule that one stage's failure stops a chained route (:mod:`.stages`).

Imports only numpy and threadpoolctl (pandas and matplotlib inside the functions that need
them); no other room of iwan_element.
"""
