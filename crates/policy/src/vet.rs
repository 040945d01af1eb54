//! What a policy graph may hold, checked on the decoded protobuf before tract builds anything from it.
//!
//! tract runs any ONNX graph; a policy file may come from anyone. So before tract sees it, the graph must be
//! what `python -m chopperscape.learn.export` writes: operators from a short list (none that sizes its output from a
//! value in the file, as `Expand`, `Tile`, `ConstantOfShape`, `Range` or `Resize` do, and none with a subgraph),
//! no external data (which tract would read from beside the file), no sparse tensors, and no tensor holding
//! more elements than the file has bytes. Every allocation tract then makes is bounded by the file's size and
//! the observation's, checked again on the typed graph's concrete shapes ([`MAX_ELEMENTS`]).

use tract_onnx::pb::{ModelProto, NodeProto, TensorProto};

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
pub const MAX_ELEMENTS: usize = 64 << 20;

fn refuse(what: impl Into<String>) -> PolicyError {
    PolicyError::NotPolicy(what.into())
}

/// Checks the whole model against the rules above; `file_len` bounds every tensor's element count.
pub fn model(proto: &ModelProto, file_len: usize) -> Result<(), PolicyError> {
    let graph = proto.graph.as_ref().ok_or_else(|| refuse("the ONNX file holds no graph"))?;
    if !graph.sparse_initializer.is_empty() {
        return Err(refuse("the graph holds sparse tensors"));
    }
    // Older IR versions list the initializers among the inputs too.
    let inputs = graph.input.iter().filter(|i| !graph.initializer.iter().any(|t| t.name == i.name)).count();
    if inputs != 1 || graph.output.len() != 1 {
        return Err(refuse(format!(
            "a policy graph has one input (the observation) and one output (the logits); this one has {inputs} and {}",
            graph.output.len()
        )));
    }
    for t in &graph.initializer {
        tensor(t, file_len)?;
    }
    for node in &graph.node {
        self::node(node, file_len)?;
    }
    Ok(())
}

fn node(node: &NodeProto, file_len: usize) -> Result<(), PolicyError> {
    let default_domain = node.domain.is_empty() || node.domain == "ai.onnx";
    if !default_domain || !OPERATORS.contains(&node.op_type.as_str()) {
        let op = if default_domain { node.op_type.clone() } else { format!("{}.{}", node.domain, node.op_type) };
        return Err(refuse(format!("the graph uses the operator {op:?}, which no exported policy uses")));
    }
    for a in &node.attribute {
        if a.g.is_some() || !a.graphs.is_empty() || a.sparse_tensor.is_some() || !a.sparse_tensors.is_empty() {
            return Err(refuse(format!("operator {:?} has a subgraph or a sparse tensor", node.op_type)));
        }
        for t in a.t.iter().chain(&a.tensors) {
            tensor(t, file_len)?;
        }
    }
    Ok(())
}

fn tensor(t: &TensorProto, file_len: usize) -> Result<(), PolicyError> {
    if t.data_location == Some(1) || !t.external_data.is_empty() || t.segment.is_some() {
        return Err(refuse(format!("tensor {:?} keeps its data outside the file, or in segments", t.name)));
    }
    let elements = t.dims.iter().try_fold(1usize, |n, &d| usize::try_from(d).ok().and_then(|d| n.checked_mul(d)));
    match elements {
        Some(n) if n <= file_len => Ok(()),
        _ => Err(refuse(format!("tensor {:?} claims dimensions {:?}, more than the file holds", t.name, t.dims))),
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
