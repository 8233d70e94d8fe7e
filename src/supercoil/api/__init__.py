"""The public API's modules: problems (:mod:`~supercoil.api.model`), verbs
(:mod:`~supercoil.api.verbs`), results (:mod:`~supercoil.api.results`) and the
continuation of a user's energy (:mod:`~supercoil.api.energy`). Import them from
:mod:`supercoil`."""
