"""The recipe's networks (`chopperscape.learn.networks`): what observations each takes, the CNN's shared trunk, and the
frames it reads (inverted since 0.2; 0.1.0's checkpoints keep plain frames)."""

from __future__ import annotations

import pytest
from conftest import needs_torch

from chopperscape.learn.recipe import NETWORKS


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


@needs_torch
def test_coords_are_coordconvs_channels_after_the_first_convolution():
    """A convolution over the frames plus two coordinate channels (CoordConv's concatenation) equals the convolution
    over the frames plus :class:`Coords` (a map linear in the output's row and column) with the matching weights."""
    import torch

    from chopperscape.learn.networks import Coords

    torch.manual_seed(0)
    c, h, w, k, s = 3, 21, 17, 4, 2
    full = torch.nn.Conv2d(c + 2, 5, k, s)
    x = torch.rand(2, c, h, w)
    rows = torch.linspace(-1, 1, h).view(1, 1, h, 1).expand(2, 1, h, w)
    cols = torch.linspace(-1, 1, w).view(1, 1, 1, w).expand(2, 1, h, w)
    want = full(torch.cat([x, rows, cols], 1))
    ho, wo = (h - k) // s + 1, (w - k) // s + 1
    conv = torch.nn.Conv2d(c, 5, k, s)
    coords = Coords(5, (ho, wo))
    with torch.no_grad():
        conv.weight.copy_(full.weight[:, :c])
        wr, wc = full.weight[:, c].sum((1, 2)), full.weight[:, c + 1].sum((1, 2))
        a, b = s * wr * (ho - 1) / (h - 1), s * wc * (wo - 1) / (w - 1)
        coords.weight.copy_(torch.stack([a, b]).view(2, 5, 1, 1))
        # The rest of the coordinate channels' response is a constant per output channel: the bias takes it.
        constant = full(torch.cat([torch.zeros(1, c, h, w), rows[:1], cols[:1]], 1))[0, :, 0, 0] - full.bias
        conv.bias.copy_(full.bias + constant + a + b)
    torch.testing.assert_close(coords(conv(x)), want, rtol=0, atol=1e-5)


@needs_torch
def test_keypoints_are_where_each_map_peaks():
    import torch

    from chopperscape.learn.networks import Keypoints

    maps = torch.zeros(1, 2, 9, 11)
    maps[0, 0, 2, 7] = 50.0  # one sharp peak per map
    maps[0, 1, 8, 0] = 50.0
    out = Keypoints((9, 11))(maps).view(1, 2, 2)
    rows, cols = torch.linspace(-1, 1, 9), torch.linspace(-1, 1, 11)
    torch.testing.assert_close(out[0, 0], torch.stack([rows[2], cols[7]]), rtol=0, atol=1e-4)
    torch.testing.assert_close(out[0, 1], torch.stack([rows[8], cols[0]]), rtol=0, atol=1e-4)
    # A flat map has its keypoint at the centre.
    assert Keypoints((9, 11))(torch.zeros(1, 1, 9, 11)).abs().max() < 1e-6


@needs_torch
@pytest.mark.parametrize("network", [n for n in NETWORKS if n.startswith("small-")])
def test_the_position_reading_networks_train_save_and_export(network, tmp_path):
    """Each variant the recipe names (every "small-" network): trained by the same loop, saved, reloaded and
    exported to the operators the policy crate takes."""
    import torch

    from chopperscape.learn import export, modelfile, train
    from chopperscape.learn.recipe import Recipe

    recipe = Recipe(
        obs_type="grayscale",
        env_options={"obs_size": [20, 20], "frame_stack": 2, "max_fuel": 120},
        network=network,
        num_envs=4,
        num_steps=16,
        num_minibatches=2,
        total_steps=4 * 16 * 2,
    )
    path = train.train(recipe, tmp_path / "run")
    loaded = modelfile.load(path)
    x = torch.randint(0, 256, (3, 20, 20, 2), dtype=torch.uint8)
    assert loaded.agent.heads(x)[0].shape == (3, 5)
    result = export.export(path, tmp_path / "p.onnx")
    assert result["bytes"] > 0 and result.get("checked") in (True, False)


@needs_torch
def test_deep_adds_one_dense_layer_of_the_trunks_width():
    """The "-deep" network is the same trunk with a second dense layer (width × width and a ReLU) before the heads."""
    from chopperscape.learn.networks import build_agent

    shape = (42, 42, 4)
    plain, deep = build_agent("small-coord", shape), build_agent("small-coord-deep", shape)
    extra = sum(p.numel() for p in deep.parameters()) - sum(p.numel() for p in plain.parameters())
    assert extra == 256 * 256 + 256
    assert deep.embedding_width == plain.embedding_width == 256


@needs_torch
def test_conv3_adds_a_third_convolution_and_norm_a_layer_norm_after_each_dense_layer():
    """ "-conv3" is the stem network with a 3×3 stride-1 convolution of 32 maps after the second (9×9 maps at 42×42
    become 7×7, so the first dense layer reads 7·7·32 inputs); "-norm" is it with a LayerNorm (a scale and a shift
    of the width each) after each of its two dense layers, before the ReLU."""
    from torch import nn

    from chopperscape.learn.networks import build_agent, parameter_count

    shape = (42, 42, 4)
    conv3, norm = build_agent("small-coord-deep-stem-conv3", shape), build_agent("small-coord-deep-stem-norm", shape)

    def count(network: str) -> int:
        return parameter_count(network, shape, 128)

    def kinds(agent, kind) -> list:
        return [m for m in agent.actor[0] if isinstance(m, kind)]

    assert [c.stride for c in kinds(conv3, nn.Conv2d)][-1] == (1, 1) and len(kinds(conv3, nn.Conv2d)) == 3
    base = count("small-coord-deep-stem")
    assert count("small-coord-deep-stem-conv3") - base == (32 * 32 * 9 + 32) + 256 * (7 * 7 * 32 - 9 * 9 * 32)
    assert len(kinds(norm, nn.LayerNorm)) == 2 and count("small-coord-deep-stem-norm") - base == 2 * 2 * 256
    trunk = list(norm.actor[0])
    for ln in kinds(norm, nn.LayerNorm):
        at = trunk.index(ln)
        assert isinstance(trunk[at - 1], nn.Linear) and isinstance(trunk[at + 1], nn.ReLU)
    assert conv3.embedding_width == norm.embedding_width == 256


@needs_torch
def test_the_stem_gives_each_frame_its_grey_bands_and_learns_nothing_itself():
    """The "-stem" network's `Stem`: frame f's band k is relu(x_f − knot_k), with the frames' pixels read as the
    network reads them (inverted); it has no parameters, so the network differs from "small-coord-deep" only in
    the first convolution's input channels (one per frame and knot)."""
    import torch

    from chopperscape.learn.networks import STEM_KNOTS, Frames, Stem, build_agent

    raw = torch.tensor([[[[255, 176], [112, 0]]]], dtype=torch.uint8).permute(0, 2, 3, 1).repeat(1, 1, 1, 3)
    raw[..., 1] = 255 - raw[..., 1]  # the second frame differs from the first and third
    x = Frames(invert=True)(raw)
    bands = Stem(3)(x)
    k = len(STEM_KNOTS)
    assert bands.shape == (1, 3 * k, 2, 2)
    for f in range(3):
        for j, knot in enumerate(STEM_KNOTS):
            torch.testing.assert_close(bands[0, f * k + j], torch.relu(x[0, f] - knot))
    # The tank (176: 0.31 inverted) shows in the second band and not the third; the chopper (112: 0.56) in both.
    assert bands[0, 1, 0, 1] > 0 and bands[0, 2, 0, 1] == 0 and bands[0, 2, 1, 0] > 0
    assert list(Stem(3).parameters()) == []
    shape = (42, 42, 4)
    plain, stem = build_agent("small-coord-deep", shape), build_agent("small-coord-deep-stem", shape)
    extra = sum(p.numel() for p in stem.parameters()) - sum(p.numel() for p in plain.parameters())
    assert extra == 16 * 4 * 4 * 4 * (k - 1)  # the first convolution's weights on the extra bands


@needs_torch
def test_the_grey_bands_are_refused_on_plain_frames():
    """Its knots are levels of inverted frames (the sky 0): on plain frames (the sky 1) every band would fire on the
    sky, so the recipe refuses the pair, naming the option and what is allowed."""
    from chopperscape.learn.recipe import Recipe, check_recipe

    with pytest.raises(ValueError, match=r"small-coord-deep-stem.*drop --no-invert-frames"):
        check_recipe(Recipe(obs_type="grayscale", network="small-coord-deep-stem", invert_frames=False))
    check_recipe(Recipe(obs_type="grayscale", network="small-coord-deep-stem"))
