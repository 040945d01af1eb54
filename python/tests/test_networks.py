"""The recipe's networks (`chopperscape.learn.networks`): what observations each takes, the CNN's shared trunk, and the
frames it reads (inverted since 0.2; 0.1.0's checkpoints keep plain frames)."""

from __future__ import annotations

import pytest
from conftest import needs_torch


def test_networks_refuse_observations_they_cannot_take():
    pytest.importorskip("torch")
    from chopperscape.learn import networks

    with pytest.raises(ValueError, match="mlp network takes vector observations"):
        networks.build_agent("mlp", (84, 84, 4))
    with pytest.raises(ValueError, match="takes grayscale frames"):
        networks.build_agent("small", (46,))
    with pytest.raises(ValueError, match="too small"):
        networks.build_agent("nature", (16, 16, 4))
    with pytest.raises(ValueError, match="allowed 'auto', 'mlp', 'small', 'nature', 'small-split'"):
        networks.build_agent("resnet", (84, 84, 4))


@needs_torch
@pytest.mark.parametrize("network, shape", [("small", (84, 84, 4)), ("small", (42, 42, 4)), ("nature", (84, 84))])
def test_cnn_act_runs_the_trunk_once_and_matches_both_heads(network, shape):
    """`CnnAgent.act` shares one trunk pass between the heads (half the convolutions of calling `actor` and
    `critic`); its log-probabilities, entropy, value and gradients are those of the two heads called apart."""
    import torch

    from chopperscape.learn import networks

    torch.manual_seed(0)
    agent = networks.build_agent(network, shape)
    x = torch.randint(0, 256, (6, *shape), dtype=torch.uint8)
    actions = torch.tensor([0, 1, 2, 3, 4, 0])
    trunk = agent.actor[0]
    calls = []
    hook = trunk.register_forward_hook(lambda *_: calls.append(1))
    _, logp, ent, value = agent.act(x, actions)
    hook.remove()
    assert len(calls) == 1
    dist = torch.distributions.Categorical(logits=agent.actor(x))
    torch.testing.assert_close(logp, dist.log_prob(actions), rtol=0, atol=1e-6)
    torch.testing.assert_close(ent, dist.entropy(), rtol=0, atol=1e-6)
    torch.testing.assert_close(value, agent.value(x), rtol=0, atol=1e-6)
    # The same gradients as the loss built from the separate heads.
    (logp.sum() + value.sum()).backward()
    shared = [p.grad.clone() for p in agent.parameters()]
    agent.zero_grad()
    (dist.log_prob(actions).sum() + agent.value(x).sum()).backward()
    for got, want in zip(shared, (p.grad for p in agent.parameters())):
        torch.testing.assert_close(got, want, rtol=1e-5, atol=1e-6)
    # Frames: uint8 and float frames in 0..255 give the same numbers, and a float input is not changed in place.
    xf = x.float()
    before = xf.clone()
    torch.testing.assert_close(agent.act(xf, actions)[1], logp.detach(), rtol=0, atol=1e-6)
    assert torch.equal(xf, before)


@needs_torch
def test_small_split_gives_the_critic_a_trunk_of_its_own(tmp_path):
    """ "small-split": the critic's trunk is its own (other weights, no shared parameter), so the value loss's
    gradient never reaches the actor's; `act` runs each trunk once and matches the heads."""
    import torch

    from chopperscape.learn import networks

    torch.manual_seed(0)
    agent = networks.build_agent("small-split", (42, 42, 4))
    actor_trunk, critic_trunk = agent.actor[0], agent.critic[0]
    assert not {id(p) for p in actor_trunk.parameters()} & {id(p) for p in critic_trunk.parameters()}
    assert not torch.equal(actor_trunk[1].weight, critic_trunk[1].weight)
    shared = networks.build_agent("small", (42, 42, 4))
    assert sum(p.numel() for p in agent.parameters()) == sum(p.numel() for p in shared.parameters()) + sum(
        p.numel() for p in shared.actor[0].parameters()
    )
    x = torch.randint(0, 256, (5, 42, 42, 4), dtype=torch.uint8)
    actions = torch.tensor([0, 1, 2, 3, 4])
    _, logp, _, value = agent.act(x, actions)
    torch.testing.assert_close(logp, torch.distributions.Categorical(logits=agent.actor(x)).log_prob(actions))
    torch.testing.assert_close(value, agent.value(x))
    value.sum().backward()
    assert all(p.grad is None for p in actor_trunk.parameters())
    assert all(p.grad is not None and p.grad.abs().sum() > 0 for p in critic_trunk.parameters())
    # With the shared trunk the same loss does reach it.
    shared.act(x, actions)[3].sum().backward()
    assert all(p.grad is not None for p in shared.actor[0].parameters())


@needs_torch
def test_cnn_reads_inverted_frames_and_old_models_keep_plain_ones(tmp_path):
    """Recipe CNNs read ``1 - frame / 255`` (the white sky as 0); a 0.1.0 checkpoint, whose recipe has no
    `invert_frames`, is rebuilt reading ``frame / 255`` and gives the logits it was saved with."""
    import torch

    from chopperscape.learn import modelfile, networks, normalize
    from chopperscape.learn.recipe import Recipe

    x = torch.tensor([[[0, 51], [255, 204]]], dtype=torch.uint8)
    torch.testing.assert_close(networks.Frames(invert=True)(x), 1 - x.unsqueeze(1).float() / 255, rtol=0, atol=1e-6)
    torch.testing.assert_close(networks.Frames()(x), x.unsqueeze(1).float() / 255, rtol=0, atol=1e-6)
    assert Recipe().invert_frames is True
    shape = (42, 42, 2)
    frames = torch.randint(0, 256, (5, *shape), dtype=torch.uint8)
    for invert in (True, False):
        torch.manual_seed(3)
        agent = networks.build_agent("small", shape, invert_frames=invert)
        recipe = Recipe(obs_type="grayscale", network="small", invert_frames=invert)
        path = tmp_path / f"invert-{invert}.pt"
        modelfile.save(path, agent, normalize.ObsNormalizer(shape, False), recipe, shape, 0)
        if not invert:  # as 0.1.0 wrote it: no such key
            payload = torch.load(path, weights_only=True)
            del payload["recipe"]["invert_frames"]
            torch.save(payload, path)
        loaded = modelfile.load(path).agent
        assert cast_frames(loaded).invert is invert
        torch.testing.assert_close(loaded.actor(frames), agent.actor(frames), rtol=0, atol=0)
    # The two readings are different inputs: the same weights give other logits.
    torch.manual_seed(3)
    plain = networks.build_agent("small", shape)
    torch.manual_seed(3)
    inverted = networks.build_agent("small", shape, invert_frames=True)
    assert not torch.allclose(plain.actor(frames), inverted.actor(frames))


def cast_frames(agent):
    """The `Frames` layer at the front of a CNN agent's trunk."""
    return agent.actor[0][0]
