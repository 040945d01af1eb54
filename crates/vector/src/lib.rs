//! Batched stepping of N ChopperScape environments.
