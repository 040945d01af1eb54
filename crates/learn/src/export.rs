//! The policy as ONNX, in the format of Python's `chopperscape.learn.export` (`chopperscape-policy/1`): input
//! `obs` `(batch, obs_dim)` raw features, the observation normalisation in the graph (`(obs − mean) · inv_std`,
//! clipped to ±10), the actor's three `Gemm`s (torch's `(outputs, inputs)` weights, `transB = 1`) with tanh
//! between, output `logits` `(batch, 5)`; the `metadata_props` that `chopperscape-policy` reads.

use prost::Message;
use sha2::{Digest, Sha256};
use tract_onnx::pb::{
    AttributeProto, GraphProto, ModelProto, NodeProto, OperatorSetIdProto, StringStringEntryProto, TensorProto,
    TensorShapeProto, TypeProto, ValueInfoProto, tensor_shape_proto, type_proto,
};

use crate::LearnError;
use crate::agent::Agent;
use crate::stats::{EPSILON, OBS_CLIP, ObsNorm};

/// The format written into `metadata_props["format"]`.
pub const FORMAT: &str = "chopperscape-policy/1";
/// The ONNX operator set (Python's export uses 17).
pub const OPSET: i64 = 17;

fn floats(name: &str, dims: &[i64], values: &[f32]) -> TensorProto {
    TensorProto {
        name: name.into(),
        dims: dims.to_vec(),
        data_type: 1,
        raw_data: values.iter().flat_map(|v| v.to_le_bytes()).collect(),
        ..Default::default()
    }
}

fn value(name: &str, width: i64) -> ValueInfoProto {
    let dim = |v| tensor_shape_proto::Dimension { value: Some(v), ..Default::default() };
    ValueInfoProto {
        name: name.into(),
        r#type: Some(TypeProto {
            value: Some(type_proto::Value::TensorType(type_proto::Tensor {
                elem_type: 1,
                shape: Some(TensorShapeProto {
                    dim: vec![
                        dim(tensor_shape_proto::dimension::Value::DimParam("batch".into())),
                        dim(tensor_shape_proto::dimension::Value::DimValue(width)),
                    ],
                }),
            })),
            ..Default::default()
        }),
        ..Default::default()
    }
}

fn node(op: &str, inputs: &[&str], output: &str, attribute: Vec<AttributeProto>) -> NodeProto {
    NodeProto {
        op_type: op.into(),
        name: output.into(),
        input: inputs.iter().map(|s| s.to_string()).collect(),
        output: vec![output.into()],
        attribute,
        ..Default::default()
    }
}

/// What the export says about the policy beside its graph.
#[derive(Clone, Debug)]
pub struct ExportInfo {
    /// The env options it was trained with, as JSON text with sorted keys in Python's spacing (`{"frame_skip": 4}`).
    pub env_options: String,
    /// The reset-seed ranges it was trained on, `(first, count)`.
    pub train_seeds: Vec<(u64, u64)>,
}

/// Python's `json.dumps(options, sort_keys=True)` for the flat options a recipe holds.
pub fn python_json(options: &serde_json::Map<String, serde_json::Value>) -> String {
    let mut keys: Vec<&String> = options.keys().collect();
    keys.sort();
    let items: Vec<String> = keys
        .iter()
        .map(|k| {
            let v = match &options[k.as_str()] {
                serde_json::Value::Array(a) => {
                    format!("[{}]", a.iter().map(|x| x.to_string()).collect::<Vec<_>>().join(", "))
                }
                other => other.to_string(),
            };
            format!("{}: {v}", serde_json::Value::from(k.as_str()))
        })
        .collect();
    format!("{{{}}}", items.join(", "))
}

/// The ONNX file of `agent`'s actor behind `norm`.
///
/// # Errors
/// Candle's, never in practice.
pub fn to_onnx(agent: &Agent, norm: &ObsNorm, info: &ExportInfo) -> Result<Vec<u8>, LearnError> {
    let dim = norm.rms.mean.len();
    let (mean, inv_std): (Vec<f32>, Vec<f32>) = if norm.enabled {
        norm.rms.mean.iter().zip(&norm.rms.var).map(|(&m, &v)| (m as f32, (1.0 / (v + EPSILON).sqrt()) as f32)).unzip()
    } else {
        (vec![0.0; dim], vec![1.0; dim])
    };
    let mut init = vec![
        floats("mean", &[dim as i64], &mean),
        floats("inv_std", &[dim as i64], &inv_std),
        floats("clip_min", &[], &[-OBS_CLIP as f32]),
        floats("clip_max", &[], &[OBS_CLIP as f32]),
    ];
    let mut hasher = Sha256::new();
    let mut nodes = vec![
        node("Sub", &["obs", "mean"], "centred", vec![]),
        node("Mul", &["centred", "inv_std"], "scaled", vec![]),
        node("Clip", &["scaled", "clip_min", "clip_max"], "x0", vec![]),
    ];
    let trans_b = AttributeProto { name: "transB".into(), i: 1, r#type: 2, ..Default::default() };
    let mut outputs = 0;
    for (k, layer) in agent.actor.layers.iter().enumerate() {
        let w: Vec<Vec<f32>> = layer.weight.as_tensor().t()?.to_vec2()?; // (outputs, inputs), torch's layout
        let b: Vec<f32> = layer.bias.as_tensor().to_vec1()?;
        let (o, i) = (w.len() as i64, w[0].len() as i64);
        let flat: Vec<f32> = w.concat();
        let (wn, bn) = (format!("actor.{}.weight", 2 * k), format!("actor.{}.bias", 2 * k));
        init.push(floats(&wn, &[o, i], &flat));
        init.push(floats(&bn, &[o], &b));
        let input = format!("x{}", 2 * k);
        let out = if k == 2 { "logits".to_string() } else { format!("g{k}") };
        nodes.push(node("Gemm", &[&input, &wn, &bn], &out, vec![trans_b.clone()]));
        if k < 2 {
            nodes.push(node("Tanh", &[&out], &format!("x{}", 2 * k + 2), vec![]));
        }
        outputs = o;
    }
    for t in &init {
        hasher.update(&t.raw_data);
    }
    let sha: String = hasher.finalize().iter().map(|b| format!("{b:02x}")).collect();
    let seeds: Vec<String> = info.train_seeds.iter().map(|(a, n)| format!("[{a}, {n}]")).collect();
    let props = [
        ("format", FORMAT.to_string()),
        ("obs_type", "features".into()),
        ("obs_shape", format!("[{dim}]")),
        ("env_options", info.env_options.clone()),
        ("features_version", chopperscape::features::FEATURES_VERSION.to_string()),
        ("pixels_version", chopperscape::render::PIXELS_VERSION.to_string()),
        ("source_sha256", sha),
        ("train_seeds", format!("[{}]", seeds.join(", "))),
    ];
    let model = ModelProto {
        ir_version: 8,
        opset_import: vec![OperatorSetIdProto { domain: String::new(), version: OPSET }],
        producer_name: "chopperscape-learn".into(),
        producer_version: env!("CARGO_PKG_VERSION").into(),
        graph: Some(GraphProto {
            name: "policy".into(),
            node: nodes,
            initializer: init,
            input: vec![value("obs", dim as i64)],
            output: vec![value("logits", outputs)],
            ..Default::default()
        }),
        metadata_props: props.into_iter().map(|(k, v)| StringStringEntryProto { key: k.into(), value: v }).collect(),
        ..Default::default()
    };
    Ok(model.encode_to_vec())
}
