"""How an effect stack is computed: the machinery below and behind the effect modules.

* :mod:`.law`, :mod:`.law_kernel`: the exact slider laws on the continuous density
  (break-away, asymmetric slip) and their compiled state table;
* :mod:`.sliders`: the slider banks of the slider-level effects whose thresholds evolve with
  the state (slip degradation), compiled per-slider steps;
* :mod:`.jenkins`: the Jenkins bank of the macroslip-onset effect;
* :mod:`.series_kernel`: the compiled whole-history route of backlash around the joint;
* :mod:`.evaluate`: the whole-history evaluator of an effect stack the diagnoses run.

The first four import only :mod:`iwan_element.effects.base` and :mod:`iwan_element.core`;
the effect modules build on them. :mod:`.evaluate` sits above the effect modules: it looks
the effects up by name in :data:`iwan_element.effects.EFFECTS`. This ``__init__`` imports
nothing, so importing an effect module never imports the evaluator.
"""
