"""The recipe presets ``--preset NAME`` names: for each, the settings that differ from
:class:`~chopperscape.learn.recipe.Recipe`'s defaults, with the measurements each was chosen by. Plain data, no torch;
:mod:`chopperscape.learn.recipe` re-exports :data:`PRESETS`, where the command lines read it.
"""

from __future__ import annotations

from typing import Any

#: Recipe presets (``--preset NAME``): the settings that differ from :class:`Recipe`'s defaults; flags given on
#: the command line win. ``pixels`` learns from the frames alone (no teacher, no features anywhere in training):
#: the 42×42 agent view (pixel layout 3), grayscale, 4 stacked, each action held for 4 frames (env steps then
#: count decisions: a decision is 4 frames); γ = 0.998 per decision is the features recipe's 0.9995 per frame
#: (0.9995⁴ ≈ 0.998), GAE λ 0.98, entropy 0.01, and 64 envs × 128 steps in 1 epoch of 16 minibatches at a
#: learning rate of 2e-3 with the value loss at weight 1.0 (twice the default's 0.5; since the twelfth session),
#: over a 12 M decision schedule (since the thirty-first session, 8 M before it; 36–43 minutes a seed alone on 2
#: cores of a Zen 5 EPYC with ``--torch-compile --torch-threads 2``, the speed settings, which the preset leaves to
#: the flags; about 100 on a Zen 3 EPYC), on ``small-coord-deep-stem``: the small CNN reading each
#: frame as three grey bands (the stem), with CoordConv's coordinates and a second dense layer
#: (:mod:`chopperscape.learn.networks`). Chosen by issue 43's probes
#: (docs/notes/pixels-speed-and-probes.md); until the ninth session the preset was the teacher-free probes' p3 (the
#: plain small CNN, 2 epochs of 4 minibatches at 1e-3 over 10 M; docs/notes/teacher-free-probes-second-round.md),
#: whose runs ``--network small --update-epochs 2 --num-minibatches 4 --learning-rate 1e-3 --steps 10000000``
#: reproduce. 84×84 with λ 0.95 did not train from frames alone here. Since the twenty-fourth session it also
#: explores by Random Network Distillation (:mod:`chopperscape.learn.novelty`; :data:`NOVELTY`): without it, one
#: seed in five stalled low in the sky and stayed there (seeds 2 and 102 of issue 43's target, 3,838 and 2,407).
#: The 12 M schedule met issue 43's target where 8 M did not (docs/curves/pixels-candidates/rndpool2-12m/: training
#: seeds 0–4 IQM 7,639, never tuned on 100–104 IQM 7,357; 8 M: 6,411 and 6,686; every seed above 4,000).
#: ``pixels-teacher`` is the earlier 84×84 recipe that `models/ppo-pixels-teacher.pt` was trained with beside a
#: features teacher (`--teacher`), the faster, privileged route.
#: What the two pixel presets share: a small CNN on grayscale frames, 4 stacked at frame skip 4, γ 0.998 a decision.
_FRAMES: dict[str, Any] = {
    "obs_type": "grayscale",
    "network": "small",
    "num_steps": 128,
    "num_minibatches": 4,
    "gamma": 0.998,
    "ent_coef": 0.01,
}
#: The exploration bonus `pixels` learns with since the twenty-fourth session: RND as the paper has it (a predictor
#: chasing a fixed random network, its error a reward with a value head of its own, weighed 0.5 against the game's),
#: the two networks reading each frame pooled 2×2 (21×21), which costs about 1.2 times the preset's time without it
#: (`python/bench_train.py --case pixels`). Chosen by issue 43's probes and target runs
#: (docs/curves/pixels-candidates/rndpool2/: held out at 8 M, seed 2 7,663 and seed 102 9,158 where the preset
#: without it had 3,838 and 2,407; docs/notes/pixels-speed-and-probes.md).
NOVELTY: dict[str, Any] = {"rnd_coef": 0.5, "rnd_own_value": True, "rnd_pool": 2}
PRESETS: dict[str, dict[str, Any]] = {
    "features": {},
    "pixels": {
        **_FRAMES,
        "env_options": {"obs_size": [42, 42], "frame_stack": 4, "frame_skip": 4},
        "network": "small-coord-deep-stem",
        "num_envs": 64,
        "update_epochs": 1,
        "num_minibatches": 16,
        "gae_lambda": 0.98,
        "learning_rate": 2e-3,
        "vf_coef": 1.0,
        "total_steps": 12_000_000,
        **NOVELTY,
    },
    "pixels-teacher": {
        **_FRAMES,
        "env_options": {"obs_size": [84, 84], "frame_stack": 4, "frame_skip": 4},
        "num_envs": 32,
        "learning_rate": 2.5e-4,
    },
}
#: Learning in minutes (`--preset fast`; docs/notes/fast-preset-probes.md): the features recipe at frame skip
#: 4 (env steps count decisions; γ = 0.998 per decision is 0.9995 per frame) for 3 M decisions, with a larger batch
#: per Python step (128 envs × 128 steps), 2 epochs of 4 minibatches (a quarter of the recipe's gradient steps per
#: sample) at a learning rate of 1e-3 and GAE λ 0.98, with the recipe's entropy 0.02. It carries its own step budget,
#: so `--preset fast` alone is the benchmark's run. Chosen by the probes in docs/curves/fast-probes/ (about 2 CPU
#: minutes a run) and checked on 20 seeds (docs/curves/fast-seeds-e02/).
PRESETS["fast"] = {
    "env_options": {"frame_skip": 4},
    "gamma": 0.998,
    "gae_lambda": 0.98,
    "num_envs": 128,
    "num_steps": 128,
    "num_minibatches": 4,
    "update_epochs": 2,
    "learning_rate": 1e-3,
    "total_steps": 3_000_000,
}
#: The pixel recipe with a batch sized for a GPU (`--preset pixels-large --device cuda`), without the novelty bonus
#: (not measured on a GPU yet; `--rnd-coef 0.5 --rnd-own-value --rnd-pool 2` adds it): 4× the envs, so that each
#: forward pass and each of the 8 minibatches (4,096 samples) keeps a GPU busy; the same samples per update per env,
#: over a 28 M-decision schedule. Measured on an H200 with 16 cores (issue 43; docs/curves/pixels-probes/gpu43-*):
#: on the 8 M schedule of `pixels` (twelfth session) 67,040 decisions a second with ``--env-threads 12
#: --torch-compile`` and 3,435 held out on seed 0 (a quarter of `pixels`' updates over the same decisions); on 28 M
#: (fourteenth session, 855 updates) 77,000–80,000 decisions a second, the schedule in 6 minutes, a training return
#: of 7,000 (over the last 1 M) after 2.3–3.7 minutes, and held out 10,656 (seed 0) and 19,065 (seed 1, at 23 M).
PRESETS["pixels-large"] = {
    **{k: v for k, v in PRESETS["pixels"].items() if k not in NOVELTY},
    "num_envs": 256,
    "num_minibatches": 8,
    "env_threads": 2,
    "total_steps": 28_000_000,
}
