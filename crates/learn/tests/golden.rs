//! The Rust learner against Python's implementation on the same numbers: the presets (`golden/recipe.json`) and
//! one batch (`golden/batch.json`: normalisers, GAE, the PPO loss and its gradients). Both are written by
//! `golden/make_golden.py`; regenerate with `python crates/learn/tests/golden/make_golden.py`.

use candle_core::{Device, Tensor};
use chopperscape::Rng;
use chopperscape_learn::Recipe;
use chopperscape_learn::agent::Agent;
use chopperscape_learn::gae::gae;
use chopperscape_learn::loss::{Batch, ppo_loss};
use chopperscape_learn::stats::ObsNorm;
use serde_json::Value;

fn golden(name: &str) -> Value {
    let path = format!("{}/tests/golden/{name}", env!("CARGO_MANIFEST_DIR"));
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

fn f32s(v: &Value) -> Vec<f32> {
    v.as_array()
        .unwrap()
        .iter()
        .flat_map(|x| x.as_array().map_or_else(|| vec![x.clone()], Clone::clone))
        .map(|x| x.as_f64().unwrap() as f32)
        .collect()
}

fn close(got: &[f32], want: &[f32], tol: f32, what: &str) {
    assert_eq!(got.len(), want.len(), "{what}: lengths");
    for (i, (g, w)) in got.iter().zip(want).enumerate() {
        assert!((g - w).abs() <= tol * (1.0 + w.abs()), "{what}[{i}]: {g} != {w}");
    }
}

#[test]
fn the_presets_are_pythons() {
    let g = golden("recipe.json");
    for name in ["fast", "features"] {
        let ours = serde_json::to_value(Recipe::preset(name).unwrap()).unwrap();
        assert_eq!(ours, g[name], "preset {name}");
    }
}

#[test]
fn the_observation_normaliser_is_pythons() {
    let g = golden("batch.json");
    let obs = f32s(&g["obs"]);
    let mut norm = ObsNorm::new(4, true);
    let mut out = vec![0.0; 12];
    norm.apply(&obs[..12], 3, true, &mut out);
    close(&out, &f32s(&g["norm_first"]), 1e-6, "first batch");
    norm.apply(&obs[12..], 3, true, &mut out);
    close(&out, &f32s(&g["norm_second"]), 1e-6, "second batch");
    let mean: Vec<f32> = norm.rms.mean.iter().map(|&x| x as f32).collect();
    close(&mean, &f32s(&g["rms"]["mean"]), 1e-6, "mean");
    assert!((norm.rms.count - g["rms"]["count"].as_f64().unwrap()).abs() < 1e-9);
}

#[test]
fn gae_is_pythons() {
    let g = &golden("batch.json")["gae"];
    let flags = |v: &Value| f32s(v).iter().map(|&x| x != 0.0).collect::<Vec<bool>>();
    let (adv, ret) = gae(
        3,
        &f32s(&g["rewards"]),
        &f32s(&g["values"]),
        &flags(&g["done"]),
        &flags(&g["valid"]),
        &f32s(&g["next_value"]),
        g["gamma"].as_f64().unwrap() as f32,
        g["lambda"].as_f64().unwrap() as f32,
    );
    close(&adv, &f32s(&g["advantages"]), 1e-6, "advantages");
    close(&ret, &f32s(&g["returns"]), 1e-6, "returns");
}

#[test]
fn the_loss_and_its_gradients_are_torchs() {
    let g = &golden("batch.json")["loss"];
    let agent = Agent::new(4, 5, 8, &mut Rng::seed_from_u64(0)).unwrap();
    // torch's (outputs, inputs) weights to ours (inputs, outputs).
    let transpose = |p: &[f32], shape: &Value| -> Vec<f32> {
        let s: Vec<usize> = shape.as_array().unwrap().iter().map(|x| x.as_u64().unwrap() as usize).collect();
        if s.len() == 1 {
            return p.to_vec();
        }
        let (o, i) = (s[0], s[1]);
        (0..i * o).map(|k| p[(k % o) * i + k / o]).collect()
    };
    let params: Vec<Vec<f32>> = g["params"]
        .as_array()
        .unwrap()
        .iter()
        .zip(g["shapes"].as_array().unwrap())
        .map(|(p, s)| transpose(&f32s(p), s))
        .collect();
    agent.set_params(&params).unwrap();
    let obs = f32s(&g["obs"]);
    let x = Tensor::from_vec(obs, (12, 4), &Device::Cpu).unwrap();
    let (logits, value) = agent.heads(&x, false).unwrap();
    let actions: Vec<u32> = g["actions"].as_array().unwrap().iter().map(|a| a.as_u64().unwrap() as u32).collect();
    let (old, adv, ret) = (f32s(&g["old_logp"]), f32s(&g["advantages"]), f32s(&g["returns"]));
    let batch = Batch { actions: &actions, old_logp: &old, advantages: &adv, returns: &ret };
    let num = |k: &str| g[k].as_f64().unwrap();
    let loss = ppo_loss(&logits, &value, &batch, num("clip"), num("ent_coef"), num("vf_coef")).unwrap();
    let total: f32 = loss.total.to_scalar().unwrap();
    close(
        &[total, loss.policy, loss.value, loss.entropy, loss.approx_kl, loss.clip_frac],
        &[
            num("total") as f32,
            num("policy") as f32,
            num("value") as f32,
            num("entropy") as f32,
            num("approx_kl") as f32,
            num("clip_frac") as f32,
        ],
        1e-5,
        "loss parts",
    );
    assert!(loss.clip_frac > 0.0, "the golden batch clips some samples");
    let grads = loss.total.backward().unwrap();
    for (k, (var, (want, shape))) in
        agent.vars().iter().zip(g["grads"].as_array().unwrap().iter().zip(g["shapes"].as_array().unwrap())).enumerate()
    {
        let got: Vec<f32> = grads.get(var.as_tensor()).unwrap().flatten_all().unwrap().to_vec1().unwrap();
        close(&got, &transpose(&f32s(want), shape), 1e-4, &format!("gradient {k}"));
    }
}
