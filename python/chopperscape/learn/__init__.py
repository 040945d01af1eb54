"""Learning ChopperScape: the PPO recipe and the tools around it (the ``train`` extra: torch, matplotlib).

Importing this package loads nothing heavy; each module says what it needs.

=====================  ====================================================================================
module                 what it holds
=====================  ====================================================================================
:mod:`.recipe`         :class:`~.recipe.Recipe` (the hyperparameters), the presets, the checks (no torch)
:mod:`.model`          the networks, the observation normaliser, the checkpoint format (read and written)
:mod:`.train`          the PPO loop in CleanRL-style sections, and ``python -m chopperscape.learn.train``
:mod:`.progress`       the learning-curve CSV's one schema: a writer and a reader (no torch)
:mod:`.evaluate`       ``python -m chopperscape.learn.evaluate``: any policy on held-out seeds
:mod:`.seeds`          ``python -m chopperscape.learn.seeds``: several training seeds, IQM and bootstrap CI
:mod:`.export`         ``python -m chopperscape.learn.export``: a recipe model as ONNX for Rust and the browser
:mod:`.plot`           ``python -m chopperscape.learn.plot``: learning curves from progress CSVs
:mod:`.video`          GIF/MP4 of evaluated episodes (``evaluate --video``)
=====================  ====================================================================================

A model file flows ``train`` → ``model.save`` → ``model.load`` ← ``evaluate``, ``export``.
"""
