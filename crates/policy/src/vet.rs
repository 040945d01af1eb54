//! What a policy graph may hold, checked on the decoded protobuf before tract builds anything from it.
//!
//! tract runs any ONNX graph; a policy file may come from anyone. So before tract sees it, the graph must be
//! what `python -m chopperscape.learn.export` writes: operators from a short list (none that sizes its output from a
//! value in the file, as `Expand`, `Tile`, `ConstantOfShape`, `Range` or `Resize` do, and none with a subgraph),
//! no external data (which tract would read from beside the file), no sparse tensors, and no tensor holding
//! more elements than the file has bytes. Every allocation tract then makes is bounded by the file's size and
//! the observation's, checked again on the typed graph's concrete shapes ([`MAX_ELEMENTS`]).

use std::collections::HashMap;

use tract_onnx::pb::{
    AttributeProto, ModelProto, NodeProto, TensorProto, ValueInfoProto, tensor_shape_proto, type_proto,
};

use crate::PolicyError;

/// The operators a policy graph may use (ONNX's default domain): what `torch.onnx` makes of the recipe's MLP
/// and CNN, the normalisation and the layout changes around them.
pub const OPERATORS: &[&str] = &[
    "Abs",
    "Add",
    "ArgMax",
    "Cast",
    "Clip",
    "Concat",
    "Constant",
    "Conv",
    "Div",
    "Flatten",
    "Gather",
    "Gemm",
    "Identity",
    "LayerNormalization",
    "LogSoftmax",
    "MatMul",
    "Max",
    "Min",
    "Mul",
    "Neg",
    "Relu",
    "Reshape",
    "Shape",
    "Sigmoid",
    "Slice",
    "Softmax",
    "Sqrt",
    "Squeeze",
    "Sub",
    "Tanh",
    "Transpose",
    "Unsqueeze",
];

/// The most elements the values of a policy's graph (its intermediate and output tensors, for one observation)
/// may hold together: 64 Mi, or 256 MiB of `f32`; the recipe's CNN on 84 × 84 × 4 frames holds about 60 Ki.
/// The values tract computes while it loads the graph (those that follow from the file's constants alone) are
/// held to the same total, checked on the protobuf before tract computes them.
pub const MAX_ELEMENTS: usize = 64 << 20;

/// The most nodes a policy graph may have: 64. The recipe's MLP has 11 and its pixel CNN 22 (24 with LayerNorm);
/// tract's analysis of a graph takes time superlinear in its length (a chain of 4,000 `Relu` took 32 s).
pub const MAX_NODES: usize = 64;

/// The most initializers (weight tensors) a graph may have: 128 (the recipe's MLP has 8, its pixel CNN 12).
pub const MAX_INITIALIZERS: usize = 128;

/// The most inputs one node may read: 8. The operators in [`OPERATORS`] take at most 3 (`Conv`, `Gemm`, `Clip`)
/// and 5 (`Slice`); a `Concat` of shape pieces takes a few. A `Concat` of 1,000 inputs hung tract's analysis.
pub const MAX_NODE_INPUTS: usize = 8;

/// The most outputs one node may have: 4 (the exports' nodes have one each; `LayerNormalization` may have 3).
pub const MAX_NODE_OUTPUTS: usize = 4;

/// The most attributes one node may carry: 16 (a `Conv` has 6).
pub const MAX_ATTRIBUTES: usize = 16;

/// The most axes a tensor of the graph may have: 8. The recipe's largest is 4 (`[batch, channels, h, w]`), and
/// ONNX runtimes commonly stop at 8. Bounds the `axis`, `axes` and `perm` attributes too.
pub const MAX_RANK: usize = 8;

/// The largest `kernel_shape`, `strides` and `dilations` entry, and the largest `pads` entry, of a `Conv`: 64.
/// The recipe's CNN uses kernels 8 and 4, strides 4 and 2, no padding; common CNNs stay under 11. A `pads` of
/// 2^63 − 1 made tract's shape arithmetic overflow (a panic in debug, a hang in release).
pub const MAX_WINDOW: i64 = 64;

/// The largest `group` of a `Conv`: 4096 (the recipe uses 1; a depthwise convolution has one per channel).
pub const MAX_GROUP: i64 = 4096;

/// The most multiply-adds one observation may cost (`Conv`, `Gemm`, `MatMul`, summed over the graph): 1 Gi.
/// The recipe's CNN costs about 3 Mi, the usual "Nature" Atari CNN about 10 Mi; at 1 Gi a step takes about a
/// second. Each `Conv`'s unfolded patches (what tract may lay out to multiply them) count as values too
/// ([`MAX_ELEMENTS`]).
pub const MAX_MULTIPLY_ADDS: u64 = 1 << 30;

fn refuse(what: impl Into<String>) -> PolicyError {
    PolicyError::NotPolicy(crate::one_line(&what.into()))
}

/// What is known of one value of the graph before tract sees it: an upper bound on its number of axes, and for a
/// value that follows from the file's constants alone (which tract computes while it loads the graph) an upper
/// bound on its elements.
#[derive(Clone, Copy)]
struct Bound {
    rank: usize,
    constant: Option<u64>,
}

/// Checks the whole model against the rules above; `file_len` bounds every tensor's element count.
pub fn model(proto: &ModelProto, file_len: usize) -> Result<(), PolicyError> {
    let graph = proto.graph.as_ref().ok_or_else(|| refuse("the ONNX file holds no graph"))?;
    if !graph.sparse_initializer.is_empty() {
        return Err(refuse("the graph holds sparse tensors"));
    }
    if graph.node.len() > MAX_NODES {
        return Err(refuse(format!(
            "the graph has {} nodes, more than the {MAX_NODES} a policy may have",
            graph.node.len()
        )));
    }
    if graph.initializer.len() > MAX_INITIALIZERS {
        return Err(refuse(format!(
            "the graph has {} initializers, more than the {MAX_INITIALIZERS} a policy may have",
            graph.initializer.len()
        )));
    }
    // Older IR versions list the initializers among the inputs too.
    let inputs: Vec<_> = graph.input.iter().filter(|i| !graph.initializer.iter().any(|t| t.name == i.name)).collect();
    if inputs.len() != 1 || graph.output.len() != 1 {
        return Err(refuse(format!(
            "a policy graph has one input (the observation) and one output (the logits); this one has {} and {}",
            inputs.len(),
            graph.output.len()
        )));
    }
    for v in graph.input.iter().chain(&graph.output).chain(&graph.value_info) {
        declared(v)?;
    }
    let mut values: HashMap<&str, Bound> = HashMap::new();
    let mut total = 0u64;
    let mut known = |name: &str, bound: u64| -> Result<(), PolicyError> {
        total = total.saturating_add(bound);
        if total > MAX_ELEMENTS as u64 {
            return Err(refuse(format!(
                "its constants make values of more than {MAX_ELEMENTS} elements while it loads (at {name:?})"
            )));
        }
        Ok(())
    };
    let mut tensors: HashMap<&str, &TensorProto> = HashMap::new();
    for t in &graph.initializer {
        tensors.insert(&t.name, t);
        let n = tensor(t, file_len)?;
        known(&t.name, n)?;
        values.insert(&t.name, Bound { rank: t.dims.len(), constant: Some(n) });
    }
    // The observation, batched: tract is given [1, obs_shape...], and the metadata's shape has 1 to 3 sizes.
    values.entry(&inputs[0].name).or_insert(Bound { rank: 4, constant: None });
    let observation = observation_elements(inputs[0]).map(|n| (inputs[0].name.as_str(), n));
    for node in &graph.node {
        let out = self::node(node, file_len, &values, &tensors, observation)?;
        if node.op_type == "Constant"
            && let (Some(name), Some(t)) = (node.output.first(), node.attribute.iter().find_map(|a| a.t.as_ref()))
        {
            tensors.insert(name, t);
        }
        for name in node.output.iter().filter(|o| !o.is_empty()) {
            if values.insert(name, out).is_some() {
                return Err(refuse(format!("the value {name:?} is made twice")));
            }
            if let Some(n) = out.constant {
                known(name, n)?;
            }
        }
    }
    if !values.contains_key(graph.output[0].name.as_str()) {
        return Err(refuse(format!("no node makes the output {:?}", graph.output[0].name)));
    }
    Ok(())
}

/// A declared value (the graph's input and output, or a `value_info`): at most [`MAX_RANK`] axes and
/// [`MAX_ELEMENTS`] elements, every size checked.
fn declared(v: &ValueInfoProto) -> Result<(), PolicyError> {
    let Some(type_proto::Value::TensorType(t)) = v.r#type.as_ref().and_then(|t| t.value.as_ref()) else {
        return Ok(());
    };
    let Some(shape) = &t.shape else { return Ok(()) };
    let too_big = || refuse(format!("the value {:?} is declared larger than a policy's values may be", v.name));
    if shape.dim.len() > MAX_RANK {
        return Err(too_big());
    }
    let mut n = 1u64;
    for d in &shape.dim {
        if let Some(tensor_shape_proto::dimension::Value::DimValue(d)) = d.value {
            let d = u64::try_from(d).map_err(|_| too_big())?;
            n = n.checked_mul(d).filter(|&n| n <= MAX_ELEMENTS as u64).ok_or_else(too_big)?;
        }
    }
    Ok(())
}

/// The elements of one observation as the graph's input declares it, where every size is declared (a named size,
/// the batch axis, counts 1: tract is given one observation); `None` otherwise.
fn observation_elements(v: &ValueInfoProto) -> Option<u64> {
    let Some(type_proto::Value::TensorType(t)) = v.r#type.as_ref().and_then(|t| t.value.as_ref()) else {
        return None;
    };
    t.shape.as_ref()?.dim.iter().try_fold(1u64, |n, d| match &d.value {
        Some(tensor_shape_proto::dimension::Value::DimValue(d)) => n.checked_mul(u64::try_from(*d).ok()?),
        Some(tensor_shape_proto::dimension::Value::DimParam(_)) => Some(n),
        None => None,
    })
}

/// The int64 values of a constant tensor (shapes, axes), if it holds them in a form this reads.
fn int64_values(t: &TensorProto) -> Option<Vec<i64>> {
    if t.data_type != 7 {
        return None;
    }
    if !t.raw_data.is_empty() {
        let chunks = t.raw_data.chunks_exact(8);
        return chunks
            .remainder()
            .is_empty()
            .then(|| chunks.map(|c| i64::from_le_bytes(c.try_into().unwrap())).collect());
    }
    Some(t.int64_data.clone())
}

/// Checks one node; gives the bound of its outputs.
fn node(
    node: &NodeProto,
    file_len: usize,
    values: &HashMap<&str, Bound>,
    tensors: &HashMap<&str, &TensorProto>,
    observation: Option<(&str, u64)>,
) -> Result<Bound, PolicyError> {
    let op = node.op_type.as_str();
    let default_domain = node.domain.is_empty() || node.domain == "ai.onnx";
    if !default_domain || !OPERATORS.contains(&op) {
        let op = if default_domain { node.op_type.clone() } else { format!("{}.{}", node.domain, node.op_type) };
        return Err(refuse(format!("the graph uses the operator {op:?}, which no exported policy uses")));
    }
    if node.input.len() > MAX_NODE_INPUTS || node.output.len() > MAX_NODE_OUTPUTS {
        return Err(refuse(format!(
            "operator {op:?} has {} inputs and {} outputs; a policy's nodes have at most {MAX_NODE_INPUTS} and \
             {MAX_NODE_OUTPUTS}",
            node.input.len(),
            node.output.len()
        )));
    }
    if node.attribute.len() > MAX_ATTRIBUTES {
        return Err(refuse(format!("operator {op:?} has more than {MAX_ATTRIBUTES} attributes")));
    }
    let mut inputs = Vec::with_capacity(node.input.len());
    for name in &node.input {
        if name.is_empty() {
            inputs.push(None);
            continue;
        }
        let b = values.get(name.as_str()).ok_or_else(|| {
            refuse(format!("operator {op:?} reads {name:?}, which no earlier node, initializer or input makes"))
        })?;
        inputs.push(Some(*b));
    }
    let mut constant_value = None;
    let mut pads_growth = 1u64;
    for a in &node.attribute {
        if a.g.is_some() || !a.graphs.is_empty() || a.sparse_tensor.is_some() || !a.sparse_tensors.is_empty() {
            return Err(refuse(format!("operator {op:?} has a subgraph or a sparse tensor")));
        }
        for t in a.t.iter().chain(&a.tensors) {
            let n = tensor(t, file_len)?;
            if a.name == "value" {
                constant_value = Some(Bound { rank: t.dims.len(), constant: Some(n) });
            }
        }
        attribute(op, a)?;
        if a.name == "pads" {
            pads_growth = a.ints.iter().fold(1u64, |g, &p| g.saturating_mul(1 + p as u64));
        }
    }
    // An int64 constant read as axes (`Squeeze`, `Unsqueeze`, `Slice`) or as a shape (`Reshape`).
    let constant_ints = |ix: usize| -> Option<usize> {
        let name = node.input.get(ix)?;
        values.get(name.as_str())?.constant.map(|n| n as usize)
    };
    let rank_of = |ix: usize| inputs.get(ix).copied().flatten().map_or(0, |b| b.rank);
    let max_rank = inputs.iter().flatten().map(|b| b.rank).max().unwrap_or(0);
    let attr_len = |name: &str| node.attribute.iter().find(|a| a.name == name).map(|a| a.ints.len());
    let rank = match op {
        "Constant" => constant_value.map_or(1, |b| b.rank),
        "Shape" | "ArgMax" | "Squeeze" => max_rank.max(1),
        "Flatten" => 2,
        "Reshape" => constant_ints(1).unwrap_or(MAX_RANK + 1),
        "Unsqueeze" => rank_of(0) + attr_len("axes").or_else(|| constant_ints(1)).unwrap_or(MAX_RANK + 1),
        "Gather" => rank_of(0) + rank_of(1),
        _ => max_rank,
    };
    if rank > MAX_RANK {
        return Err(refuse(format!(
            "operator {op:?} makes values of more than {MAX_RANK} axes, or of axes that do not follow from the file"
        )));
    }
    // Axes given as int64 constants (`Squeeze`, `Unsqueeze` and `Slice` since opset 13), and `Slice`'s steps.
    let ints_at =
        |ix: usize| node.input.get(ix).and_then(|name| tensors.get(name.as_str())).and_then(|t| int64_values(t));
    let axes = match op {
        "Squeeze" | "Unsqueeze" => ints_at(1),
        "Slice" => ints_at(3),
        _ => None,
    };
    if axes.is_some_and(|a| a.len() > MAX_RANK || a.iter().any(|&x| x.unsigned_abs() > MAX_RANK as u64)) {
        return Err(refuse(format!("operator {op:?} names axes beyond the {MAX_RANK} a policy's values may have")));
    }
    if op == "Slice" && ints_at(4).is_some_and(|steps| steps.contains(&0)) {
        return Err(refuse("operator \"Slice\" has a step of 0"));
    }
    if op == "Reshape"
        && let Some(shape) = ints_at(1)
    {
        // The input's elements where they are known: a value of the file's constants, or the observation itself.
        let data = node.input.first().map(String::as_str);
        let elements = inputs
            .first()
            .copied()
            .flatten()
            .and_then(|b| b.constant)
            .or_else(|| observation.and_then(|(name, n)| (data == Some(name)).then_some(n)));
        reshape(&shape, elements)?;
    }
    // Elements of a value that follows from constants alone (tract computes it while it loads the graph).
    let all_known = !node.input.is_empty() && inputs.iter().flatten().all(|b| b.constant.is_some());
    let known = |b: &Option<Bound>| b.and_then(|b| b.constant).unwrap_or(1);
    let constant = match op {
        "Constant" => Some(constant_value.and_then(|b| b.constant).unwrap_or_else(|| {
            node.attribute.iter().map(|a| a.ints.len().max(a.floats.len()).max(1) as u64).max().unwrap_or(1)
        })),
        "Shape" => Some(rank_of(0) as u64),
        _ if !all_known => None,
        "Concat" => Some(inputs.iter().map(known).fold(0u64, u64::saturating_add)),
        "Add" | "Sub" | "Mul" | "Div" | "Max" | "Min" | "MatMul" | "Gemm" | "Gather" => {
            Some(inputs.iter().map(known).fold(1u64, u64::saturating_mul))
        }
        "Conv" => Some(inputs.iter().map(known).fold(pads_growth, u64::saturating_mul)),
        _ => Some(known(&inputs[0])),
    };
    Ok(Bound { rank, constant })
}
/// Checks a `Reshape`'s constant target `shape`: sizes of at least −1 (−1: inferred, at most once; 0: the input's
/// size on that axis), whose fixed sizes multiply (checked) to at most [`MAX_ELEMENTS`], and that can hold the
/// input's `elements` where they are known (a value of the file's constants). A 46-value observation reshaped to
/// 2^40 × 2^40 (or 2^32 × 2^32, whose product wraps to 0 in 64 bits) was accepted and played.
fn reshape(shape: &[i64], elements: Option<u64>) -> Result<(), PolicyError> {
    let bad = |why: &str| refuse(format!("operator \"Reshape\" has the shape {shape:?}, {why}"));
    let mut inferred = 0;
    let mut copied = false;
    let mut fixed = 1u64;
    for &d in shape {
        match d {
            -1 => inferred += 1,
            0 => copied = true,
            d if d > 0 => {
                fixed = fixed
                    .checked_mul(d as u64)
                    .filter(|&n| n <= MAX_ELEMENTS as u64)
                    .ok_or_else(|| bad(&format!("more than the {MAX_ELEMENTS} elements a policy's values may hold")))?;
            }
            _ => return Err(bad("a size below -1")),
        }
    }
    if inferred > 1 {
        return Err(bad("more than one size to infer (-1)"));
    }
    if let (Some(n), false) = (elements, copied) {
        let holds = if inferred == 1 { n % fixed == 0 } else { n == fixed };
        if !holds {
            return Err(bad(&format!("which cannot hold its input's {n} elements")));
        }
    }
    Ok(())
}

/// Checks one tensor of the file (an initializer, a `Constant`'s value): its data inside the file, at most
/// [`MAX_RANK`] axes and no more elements than the file has bytes. Gives its elements.
fn tensor(t: &TensorProto, file_len: usize) -> Result<u64, PolicyError> {
    if t.data_location == Some(1) || !t.external_data.is_empty() || t.segment.is_some() {
        return Err(refuse(format!("tensor {:?} keeps its data outside the file, or in segments", t.name)));
    }
    let elements = t.dims.iter().try_fold(1u64, |n, &d| u64::try_from(d).ok().and_then(|d| n.checked_mul(d)));
    match elements {
        Some(n) if n <= file_len as u64 && t.dims.len() <= MAX_RANK => Ok(n),
        _ => Err(refuse(format!("tensor {:?} claims dimensions {:?}, more than the file holds", t.name, t.dims))),
    }
}

/// Checks the attributes that size or index something against the limits above.
fn attribute(op: &str, a: &AttributeProto) -> Result<(), PolicyError> {
    let bad = |allowed: &str| {
        let value = if a.ints.is_empty() { format!("{}", a.i) } else { format!("{:?}", a.ints) };
        let value = if value.len() > 80 { format!("{}…", &value[..80]) } else { value };
        refuse(format!("operator {op:?} has {} = {value}; a policy's is {allowed}", a.name))
    };
    let rank = MAX_RANK as i64;
    let all_in = |max_len: usize, range: std::ops::RangeInclusive<i64>| {
        a.ints.len() <= max_len && a.ints.iter().all(|v| range.contains(v))
    };
    match a.name.as_str() {
        "pads" if !all_in(2 * MAX_RANK, 0..=MAX_WINDOW) => {
            Err(bad(&format!("at most {} sizes in 0..={MAX_WINDOW}", 2 * MAX_RANK)))
        }
        "kernel_shape" | "strides" | "dilations" if !all_in(MAX_RANK, 1..=MAX_WINDOW) => {
            Err(bad(&format!("at most {MAX_RANK} sizes in 1..={MAX_WINDOW}")))
        }
        "group" if !(1..=MAX_GROUP).contains(&a.i) => Err(bad(&format!("in 1..={MAX_GROUP}"))),
        "axis" if !(-rank..=rank).contains(&a.i) => Err(bad(&format!("in -{MAX_RANK}..={MAX_RANK}"))),
        "axes" if !all_in(MAX_RANK, -rank..=rank) => {
            Err(bad(&format!("at most {MAX_RANK} axes in -{MAX_RANK}..={MAX_RANK}")))
        }
        "perm" => {
            // A permutation of 0..n (tract indexed out of bounds, or allocated 4 GB, on others).
            let n = a.ints.len();
            let mut seen = [false; MAX_RANK];
            let ok = n <= MAX_RANK
                && a.ints
                    .iter()
                    .all(|&p| usize::try_from(p).is_ok_and(|p| p < n && !std::mem::replace(&mut seen[p], true)));
            if ok { Ok(()) } else { Err(bad(&format!("a permutation of at most {MAX_RANK} axes"))) }
        }
        _ => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use tract_onnx::pb::{AttributeProto, GraphProto, ValueInfoProto};

    fn graph_with(node: NodeProto) -> ModelProto {
        let io = |name: &str| ValueInfoProto { name: name.into(), ..ValueInfoProto::default() };
        ModelProto {
            graph: Some(GraphProto {
                node: vec![node],
                input: vec![io("obs")],
                output: vec![io("logits")],
                ..GraphProto::default()
            }),
            ..ModelProto::default()
        }
    }

    #[test]
    fn operators_that_size_outputs_from_data_are_refused() {
        let node = NodeProto { op_type: "ConstantOfShape".into(), ..NodeProto::default() };
        let err = model(&graph_with(node), 100).unwrap_err().to_string();
        assert!(err.contains("\"ConstantOfShape\""), "{err}");
        let custom = NodeProto { op_type: "Relu".into(), domain: "com.example".into(), ..NodeProto::default() };
        assert!(model(&graph_with(custom), 100).unwrap_err().to_string().contains("com.example.Relu"));
    }

    #[test]
    fn a_tensor_larger_than_the_file_is_refused() {
        let big = TensorProto { dims: vec![1 << 20, 1 << 20], ..TensorProto::default() };
        let node = NodeProto {
            op_type: "Constant".into(),
            attribute: vec![AttributeProto { name: "value".into(), t: Some(big), ..AttributeProto::default() }],
            ..NodeProto::default()
        };
        assert!(model(&graph_with(node), 1000).unwrap_err().to_string().contains("more than the file holds"));
        let negative = TensorProto { dims: vec![-1], ..TensorProto::default() };
        assert!(tensor(&negative, 1000).is_err());
    }

    #[test]
    fn external_data_and_subgraphs_are_refused() {
        let external = TensorProto { data_location: Some(1), ..TensorProto::default() };
        assert!(tensor(&external, 1000).unwrap_err().to_string().contains("outside the file"));
        let node = NodeProto {
            op_type: "Relu".into(),
            attribute: vec![AttributeProto { g: Some(GraphProto::default()), ..AttributeProto::default() }],
            ..NodeProto::default()
        };
        assert!(model(&graph_with(node), 100).unwrap_err().to_string().contains("subgraph"));
    }
}
