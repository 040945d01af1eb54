"""ChopperScape in other libraries' terms. Each module needs its library (an extra) and nothing else here does.

=====================  ====================================================================================
module                 what it holds
=====================  ====================================================================================
:mod:`.sb3`            Stable-Baselines3: the native batch as an SB3 ``VecEnv``, normalisation files as data
:mod:`.rllib`          Ray RLlib: the env by name for the new API stack, the native batch per env runner
:mod:`.datasets`       Minari: datasets from policies and from action logs (``chopperscape dataset``)
=====================  ====================================================================================
"""
