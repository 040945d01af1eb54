"""PPO's small pieces that the loop calls by name: the learning rate's and the entropy weight's schedules over env
steps, and the update's statistics, kept by name and averaged over its minibatches."""

from __future__ import annotations

from .recipe import Recipe


def learning_rate(recipe: Recipe, env_steps: int) -> float:
    """The rate at `env_steps`: it follows env steps only, so the same run on a busy host is the same run. Annealed,
    it falls linearly over `total_steps` to `lr_floor` of itself (`LR_FLOOR`, 5 %, unless the recipe says)."""
    lr = recipe.learning_rate
    if recipe.anneal_lr:
        lr *= max(1.0 - env_steps / recipe.total_steps, recipe.lr_floor)
    return lr


def entropy_coef(recipe: Recipe, env_steps: int) -> float:
    """The entropy weight at `env_steps`: `ent_coef` falling linearly over `total_steps` to `ent_floor` of itself
    (constant at the default floor of 1). It follows env steps only, as the learning rate does."""
    done = min(env_steps / recipe.total_steps, 1.0)
    return recipe.ent_coef * (1.0 - (1.0 - recipe.ent_floor) * done)


class UpdateStats:
    """Per-minibatch diagnostics of one update (entropy, approximate KL, clip fraction, losses, and whatever the
    recipe's parts add), summed by name and read back as means over the minibatches."""

    def __init__(self) -> None:
        self.sums: dict[str, float] = {}
        self.minibatches = 0

    def add(self, values: dict[str, float]) -> None:
        """One minibatch's values."""
        self.minibatches += 1
        for name, value in values.items():
            self.sums[name] = self.sums.get(name, 0.0) + value

    def mean(self, name: str) -> float:
        return self.sums[name] / max(self.minibatches, 1)

    def columns(self, formats: dict[str, str]) -> dict[str, str]:
        """The means as progress columns, each formatted as `formats` says (`.4f`, …); a name with no format is
        written with 5 decimals (the guidance's `aux_loss`, `teacher_kl`)."""
        return {name: format(self.mean(name), formats.get(name, ".5f")) for name in self.sums}
