"""Learning ChopperScape: the PPO recipe and the tools around it (the ``train`` extra: torch, matplotlib).

Importing this package loads nothing heavy; each module says what it needs.

=====================  ====================================================================================
module                 what it holds
=====================  ====================================================================================
:mod:`.recipe`         :class:`~.recipe.Recipe` (the hyperparameters), the presets, the checks (no torch)
:mod:`.flags`          the training flags as a checked :class:`~.recipe.Recipe`, for ``train`` and ``seeds`` (no torch)
:mod:`.model`          the networks, the observation normaliser, the checkpoint format (read and written)
:mod:`.train`          the PPO loop in CleanRL-style sections, and ``python -m chopperscape.learn.train``
:mod:`.guidance`       pixel recipes' guidance from the game's features (auxiliary loss, teacher), a loop part
:mod:`.phases`         the loop's per-phase stopwatch
:mod:`.progress`       the learning-curve CSV's one schema: a writer and a reader (no torch)
:mod:`.episodes`       a policy played on seeds, its episodes summarised in constant memory
:mod:`.players`        what plays: a model file (recipe ``.pt``, SB3 ``.zip``) or a built-in policy, as ``act``
:mod:`.evaluate`       ``python -m chopperscape.learn.evaluate``: any policy on held-out seeds
:mod:`.seeds`          ``python -m chopperscape.learn.seeds``: several training seeds, each a ``train`` run
:mod:`.summary`        the seeds' evaluations and curves checked, and their summary files
:mod:`.stats`          the IQM and its percentile bootstrap confidence interval (numpy)
:mod:`.export`         ``python -m chopperscape.learn.export``: a recipe model as ONNX for Rust and the browser
:mod:`.plot`           ``python -m chopperscape.learn.plot``: learning curves from progress CSVs
:mod:`.video`          GIF/MP4 of evaluated episodes (``evaluate --video``)
=====================  ====================================================================================

A model file flows ``train`` → ``model.save`` → ``model.load`` ← ``players``, ``export``. The commands sit on top:
what two of them share is a module below both, and ``seeds`` runs ``train`` as a child process.
"""
