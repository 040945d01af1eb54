"""Learning ChopperScape: the PPO recipe and the tools around it (the ``train`` extra: torch, matplotlib).

Importing this package loads nothing heavy; each module says what it needs.

=====================  ====================================================================================
module                 what it holds
=====================  ====================================================================================
:mod:`.recipe`         :class:`~.recipe.Recipe` (the hyperparameters), the presets, the checks (no torch)
:mod:`.flags`          the training flags as a checked :class:`~.recipe.Recipe`, for ``train`` and ``seeds`` (no torch)
:mod:`.networks`       the networks: the features MLP, the CNNs on frames, ``build_agent``
:mod:`.normalize`      running statistics: the observation normaliser and the reward scaler (no torch)
:mod:`.augment`        the minibatches' augmentation (random shift), chosen from the recipe
:mod:`.modelfile`      the model file ``model.pt``: its format, written and read with every field checked
:mod:`.parts`          the recipe's variants decided once: network, encoding, augmentation, guidance
:mod:`.rollout`        an update's buffers, GAE, the update's batch, and the run's finished episodes
:mod:`.state`          the training state in one object that saves and restores itself (``resume.pt``)
:mod:`.run`            a run's folder, checkpoints, signals and clean-up: one context manager
:mod:`.ppo`            the learning-rate schedule and the update's statistics by name
:mod:`.train`          the PPO loop in CleanRL-style sections, and ``python -m chopperscape.learn.train``
:mod:`.guidance`       pixel recipes' guidance from the game's features (auxiliary loss, teacher), a loop part
:mod:`.selfsup`        a self-supervised loss from the frames alone (reconstruction), a loop part
:mod:`.phases`         the loop's per-phase stopwatch (wrappers around what the loop calls)
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

A model file flows ``train`` → ``run`` → ``modelfile.save`` → ``modelfile.load`` ← ``players``, ``export``. The
commands sit on top: what two of them share is a module below both, and ``seeds`` runs ``train`` as a child
process.
"""
