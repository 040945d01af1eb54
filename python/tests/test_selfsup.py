"""`--recon-coef`: the self-supervised loss from the frames alone (`chopperscape.learn.selfsup`). Its target is the
frame the network saw; it trains, resumes (tests/test_resume.py) and leaves the saved policy as it is; it is refused
where it means nothing; older run folders (no decoder, no `recon_loss` column) still resume."""

from __future__ import annotations

import importlib.util
import json

import pytest
from conftest import pixel_recipe

pytestmark = pytest.mark.skipif(
    importlib.util.find_spec("torch") is None, reason="torch is not installed (scripts/test-python.sh installs it)"
)


def _recipe(**kw):
    return pixel_recipe(**{"total_steps": 4 * 16 * 6, **kw})


def test_the_target_is_the_latest_frame_as_the_network_reads_it_at_half_size():
    import torch

    from chopperscape.learn.selfsup import Reconstruction

    x = torch.full((2, 4, 6, 3), 255, dtype=torch.uint8)  # white sky: 0 once inverted
    x[0, 0:2, 2:4, -1] = 0  # a black 2×2 sprite in the latest frame
    x[0, 2:4, 0:2, 0] = 0  # and one in an older frame, which the target leaves out
    rec = Reconstruction(1.0, 8, (4, 6, 3), invert=True, device="cpu")
    t = rec.target(x)
    assert t.shape == (2, 2 * 3)
    assert t[0].tolist() == [0.0, 1.0, 0.0, 0.0, 0.0, 0.0] and t[1].abs().sum() == 0
    plain = Reconstruction(1.0, 8, (4, 6, 3), invert=False, device="cpu").target(x)
    assert torch.allclose(plain, 1.0 - t)
    single = rec.target(x[..., -1])  # one frame, no stack axis
    assert torch.equal(single, t)


def test_the_loss_is_the_weighted_error_and_trains_the_embedding():
    import torch

    from chopperscape.learn.selfsup import Reconstruction

    rec = Reconstruction(3.0, 8, (4, 6, 2), invert=True, device="cpu")
    x = torch.randint(0, 256, (5, 4, 6, 2), dtype=torch.uint8)
    h = torch.randn(5, 8, requires_grad=True)
    loss, logged = rec.loss(x, h)
    err = ((rec.decoder(h) - rec.target(x)) ** 2).mean()
    assert torch.allclose(loss, 3.0 * err) and logged == {"recon_loss": pytest.approx(err.item())}
    loss.backward()
    assert h.grad is not None and h.grad.abs().sum() > 0  # the embedding (the trunk) is what it teaches
    with pytest.raises(ValueError, match="needs the network's embedding"):
        rec.loss(x, None)


def test_a_run_with_it_logs_it_and_saves_the_same_kind_of_policy(tmp_path):
    import csv

    import torch

    from chopperscape.learn import train

    plain = train.train(_recipe(), tmp_path / "plain")
    rec = train.train(_recipe(recon_coef=2.0), tmp_path / "recon")
    with open(tmp_path / "recon" / "progress.csv", newline="") as f:
        losses = [float(r["recon_loss"]) for r in csv.DictReader(f)]
    assert len(losses) == 6 and losses[-1] < losses[0]  # the decoder learns the frames
    a, b = torch.load(plain, weights_only=True), torch.load(rec, weights_only=True)
    assert set(a) == set(b) and set(a["actor"]) == set(b["actor"])  # no decoder in the policy file
    saved = json.loads((tmp_path / "recon" / "recipe.json").read_text())
    assert saved["recon_coef"] == 2.0


def test_it_is_refused_where_it_means_nothing_before_anything_is_written(tmp_path):
    from chopperscape.learn import train
    from chopperscape.learn.recipe import Recipe

    with pytest.raises(ValueError, match=r"`recon_coef`: the reconstruction loss is for CNN recipes"):
        train.train(Recipe(recon_coef=1.0), tmp_path / "a")
    with pytest.raises(ValueError, match=r"recon_coef"):
        train.train(_recipe(recon_coef=-1.0), tmp_path / "b")
    assert not (tmp_path / "a").exists() and not (tmp_path / "b").exists()


def test_older_resume_states_still_resume_and_a_decoder_goes_only_where_it_belongs():
    """A resume.pt written before the part existed holds no `frames_loss`: it resumes a recipe without one. A
    state with a decoder does not load into a run without one, and the other way round."""
    from chopperscape.learn.recipe import Recipe
    from chopperscape.learn.rundir import recipe_hash
    from chopperscape.learn.selfsup import NoFramesLoss, Reconstruction
    from chopperscape.learn.state import LATER_FIELDS

    assert LATER_FIELDS == {"frames_loss": None, "novelty": None}
    NoFramesLoss().load_state_dict(LATER_FIELDS["frames_loss"])
    rec = Reconstruction(1.0, 8, (4, 6, 2), invert=True, device="cpu")
    with pytest.raises(ValueError, match="holds a reconstruction decoder"):
        NoFramesLoss().load_state_dict(rec.state_dict())
    with pytest.raises(ValueError, match="holds no reconstruction decoder"):
        rec.load_state_dict(None)
    # The setting is out of the hash at 0, so older recipe.json files still match their resume states.
    from dataclasses import asdict

    old = {k: v for k, v in asdict(Recipe()).items() if k not in ("recon_coef", "torch_compile")}
    assert recipe_hash(Recipe()) == recipe_hash(old)
    assert recipe_hash(_recipe(recon_coef=1.0)) != recipe_hash(_recipe())


def test_a_run_folder_of_an_earlier_version_resumes(tmp_path, monkeypatch):
    """The whole path: a run whose resume.pt has no `frames_loss` and whose CSV has no `recon_loss` column (as
    earlier versions wrote them) resumes and goes on."""
    import csv

    import torch

    import chopperscape.learn.run as run
    from chopperscape.learn import progress, train

    recipe = _recipe(total_steps=4 * 16 * 4)
    out = tmp_path / "old"
    monkeypatch.setattr(run, "CHECKPOINT_EVERY", 2)
    train.train(recipe, out, until=4 * 16 * 2)
    saved = torch.load(out / "resume.pt", weights_only=True)
    del saved["state"]["frames_loss"]
    torch.save(saved, out / "resume.pt")
    with open(out / "progress.csv", newline="") as f:
        rows = list(csv.reader(f))
    with open(out / "progress.csv", "w", newline="") as f:
        csv.writer(f).writerows([r[: len(progress.OLDER_COLUMNS)] for r in rows])
    train.train(recipe, out, resume=True)
    with open(out / "progress.csv", newline="") as f:
        done = list(csv.DictReader(f))
    assert len(done) == 4 and all(r["recon_loss"] == "" for r in done)


def test_making_the_decoder_leaves_torchs_random_stream_as_it_is():
    """The decoder draws its initial weights from a generator of its own: turning the loss on changes neither the
    network's initial weights nor the actions sampled after it."""
    import torch

    from chopperscape.learn.selfsup import Reconstruction

    torch.manual_seed(7)
    expected = torch.rand(3)
    torch.manual_seed(7)
    a = Reconstruction(1.0, 16, (8, 8, 2), invert=True, device="cpu")
    assert torch.equal(torch.rand(3), expected)
    b = Reconstruction(1.0, 16, (8, 8, 2), invert=True, device="cpu")
    assert torch.equal(a.decoder.weight, b.decoder.weight) and a.decoder.weight.abs().max() <= 0.25
