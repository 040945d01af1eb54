//! Hostile policy files (issue 32): graphs that made tract hang, abort on a huge allocation, take time
//! superlinear in their size or panic, and metadata that asked for huge observations. Each is built here from
//! bytes (the committed policy's metadata around a small graph), and each must be refused fast with an error
//! that names what is wrong, before tract optimises or runs anything.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::time::{Duration, Instant};

use chopperscape_policy::{Policy, PolicyError};
use prost::Message;
use tract_onnx::pb::{
    AttributeProto, GraphProto, ModelProto, NodeProto, StringStringEntryProto, TensorProto, TensorShapeProto,
    TypeProto, ValueInfoProto, tensor_shape_proto, type_proto,
};

/// The system allocator, noting the largest allocation each thread asks for: loading a hostile file must not
/// ask for much before it is refused.
struct Noting;

thread_local! {
    static LARGEST: Cell<usize> = const { Cell::new(0) };
}

// SAFETY: forwards to the system allocator unchanged; the thread-local is a const-initialised `Cell` (no
// allocation, no destructor), read with `try_with` so that it is never touched after the thread's end.
unsafe impl GlobalAlloc for Noting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let _ = LARGEST.try_with(|l| l.set(l.get().max(layout.size())));
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let _ = LARGEST.try_with(|l| l.set(l.get().max(new_size)));
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static ALLOCATOR: Noting = Noting;

/// The most one allocation may ask for while a hostile file is refused: 64 MiB (the largest a legit load makes
/// is the file's copy and its weights, a few MiB).
const MAX_ALLOCATION: usize = 64 << 20;

const FEATURES: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../models/ppo-features.onnx");

/// The committed features policy, decoded: its metadata, opset and IR version frame each hostile graph.
fn committed() -> ModelProto {
    ModelProto::decode(&*std::fs::read(FEATURES).unwrap()).unwrap()
}

/// A float tensor value `name` of shape `dims`.
fn value(name: &str, dims: &[i64]) -> ValueInfoProto {
    let dim = |d: i64| tensor_shape_proto::Dimension {
        value: Some(tensor_shape_proto::dimension::Value::DimValue(d)),
        ..Default::default()
    };
    ValueInfoProto {
        name: name.into(),
        r#type: Some(TypeProto {
            value: Some(type_proto::Value::TensorType(type_proto::Tensor {
                elem_type: 1,
                shape: Some(TensorShapeProto { dim: dims.iter().map(|&d| dim(d)).collect() }),
            })),
            ..Default::default()
        }),
        ..Default::default()
    }
}

fn ints(name: &str, v: &[i64]) -> AttributeProto {
    AttributeProto { name: name.into(), ints: v.to_vec(), r#type: 7, ..Default::default() }
}

fn int(name: &str, v: i64) -> AttributeProto {
    AttributeProto { name: name.into(), i: v, r#type: 2, ..Default::default() }
}

fn node(op: &str, inputs: &[&str], output: &str, attribute: Vec<AttributeProto>) -> NodeProto {
    NodeProto {
        op_type: op.into(),
        input: inputs.iter().map(|s| s.to_string()).collect(),
        output: vec![output.into()],
        attribute,
        ..Default::default()
    }
}

/// A float tensor `name` of shape `dims` holding `values` (raw little-endian data).
fn floats(name: &str, dims: &[i64], values: &[f32]) -> TensorProto {
    TensorProto {
        name: name.into(),
        dims: dims.to_vec(),
        data_type: 1,
        raw_data: values.iter().flat_map(|v| v.to_le_bytes()).collect(),
        ..Default::default()
    }
}

/// An int64 tensor `name` holding `values` (a 1-D shape or axes list).
fn int64s(name: &str, values: &[i64]) -> TensorProto {
    TensorProto {
        name: name.into(),
        dims: vec![values.len() as i64],
        data_type: 7,
        raw_data: values.iter().flat_map(|v| v.to_le_bytes()).collect(),
        ..Default::default()
    }
}

/// The committed policy's frame (metadata: features [46]) around `nodes` from `obs` ([1, 46]) to `logits`.
fn model(nodes: Vec<NodeProto>, initializer: Vec<TensorProto>) -> Vec<u8> {
    let mut m = committed();
    m.graph = Some(GraphProto {
        name: "hostile".into(),
        node: nodes,
        initializer,
        input: vec![value("obs", &[1, 46])],
        output: vec![value("logits", &[1, 5])],
        ..Default::default()
    });
    m.encode_to_vec()
}

/// The committed policy's metadata with `key` set to `value`, around its own graph.
fn with_metadata(changes: &[(&str, &str)]) -> Vec<u8> {
    let mut m = committed();
    for (key, value) in changes {
        m.metadata_props.retain(|e| e.key != *key);
        m.metadata_props.push(StringStringEntryProto { key: key.to_string(), value: value.to_string() });
    }
    m.encode_to_vec()
}

/// Loads `bytes`, which must fail fast (2 s, in debug builds too), without any large allocation, with a
/// one-line error; gives the error.
fn refused(what: &str, bytes: &[u8]) -> PolicyError {
    LARGEST.with(|l| l.set(0));
    let start = Instant::now();
    let result = Policy::from_bytes(bytes);
    let took = start.elapsed();
    let largest = LARGEST.with(Cell::get);
    let err = result.expect_err(what);
    let text = err.to_string();
    eprintln!("{what}: {} bytes refused in {took:?} (largest allocation {largest} bytes): {text}", bytes.len());
    assert!(took < Duration::from_secs(2), "{what}: took {took:?}");
    assert!(largest <= MAX_ALLOCATION.max(2 * bytes.len()), "{what}: allocated {largest} bytes");
    assert!(!text.contains('\n') && text.len() < 1000, "{what}: {text:?}");
    err
}

/// A chain of `n` `Relu` from the observation, sliced to 5 logits: a valid policy of `n + 1` nodes.
fn relu_chain(n: usize) -> Vec<u8> {
    let mut nodes = vec![];
    for i in 0..n {
        let input = if i == 0 { "obs".to_string() } else { format!("r{}", i - 1) };
        nodes.push(node("Relu", &[&input], &format!("r{i}"), vec![]));
    }
    let last = format!("r{}", n - 1);
    nodes.push(node("Slice", &[&last, "starts", "ends", "axes"], "logits", vec![]));
    model(nodes, vec![int64s("starts", &[0]), int64s("ends", &[5]), int64s("axes", &[1])])
}

#[test]
fn a_conv_with_huge_pads_is_refused() {
    let reshape = node("Reshape", &["obs", "shape"], "x", vec![]);
    let weights = vec![floats("w", &[1, 1, 1], &[1.0]), int64s("shape", &[1, 1, 46])];
    let bytes = model(
        vec![
            reshape.clone(),
            node("Conv", &["x", "w"], "y", vec![ints("pads", &[i64::MAX, i64::MAX])]),
            node("Flatten", &["y"], "logits", vec![]),
        ],
        weights.clone(),
    );
    let err = refused("pads 2^63-1", &bytes).to_string();
    assert!(err.contains("operator \"Conv\" has pads = [9223372036854775807, 9223372036854775807]"), "{err}");
    for attribute in [
        ints("strides", &[0]),
        ints("dilations", &[1 << 40]),
        ints("kernel_shape", &[-1]),
        int("group", 0),
        ints("pads", &[-1, 0]),
        ints("pads", &[0; 17]),
    ] {
        let name = attribute.name.clone();
        let conv = node("Conv", &["x", "w"], "logits", vec![attribute]);
        let err = refused(&name, &model(vec![reshape.clone(), conv], weights.clone())).to_string();
        assert!(err.contains(&format!("has {name} = ")), "{err}");
    }
}

#[test]
fn axes_and_perms_out_of_range_are_refused() {
    // tract indexed out of bounds, divided by zero, or asked for 4 GB (an abort, on `perm` [0, 0]).
    let cases = [
        (node("Transpose", &["obs"], "logits", vec![ints("perm", &[0, 0])]), vec![], "perm = [0, 0]"),
        (node("Transpose", &["obs"], "logits", vec![ints("perm", &[5, 0])]), vec![], "perm = [5, 0]"),
        (node("Flatten", &["obs"], "logits", vec![int("axis", 9)]), vec![], "axis = 9"),
        (node("Unsqueeze", &["obs", "a"], "logits", vec![]), vec![int64s("a", &[-70])], "names axes beyond the 8"),
        (
            node("Slice", &["obs", "a", "a", "b", "a"], "logits", vec![]),
            vec![int64s("a", &[0]), int64s("b", &[1])],
            "a step of 0",
        ),
        (node("Reshape", &["obs", "s"], "logits", vec![]), vec![int64s("s", &[1; 9])], "more than 8 axes"),
    ];
    for (node, weights, message) in cases {
        let err = refused(message, &model(vec![node], weights)).to_string();
        assert!(err.contains(message), "{err}");
    }
}

#[test]
fn a_reshape_to_a_shape_that_cannot_hold_its_input_is_refused() {
    // A 46-value observation reshaped to 2^40 × 2^40 (or 2^32 × 2^32, whose product wraps to 0 in 64 bits) and
    // flattened back was accepted, and played (issue 45).
    let back = node("Reshape", &["x", "flat"], "y", vec![]);
    let slice = node("Slice", &["y", "starts", "ends", "axes"], "logits", vec![]);
    // The observation reshaped to `shape`, flattened back and sliced to the five logits.
    let reshaped = |shape: &[i64]| {
        let nodes = vec![node("Reshape", &["obs", "s"], "x", vec![]), back.clone(), slice.clone()];
        let weights = vec![
            int64s("s", shape),
            int64s("flat", &[1, -1]),
            int64s("starts", &[0]),
            int64s("ends", &[5]),
            int64s("axes", &[1]),
        ];
        model(nodes, weights)
    };
    for (shape, message) in [
        (vec![1 << 40, 1 << 40], "more than the 67108864 elements"),
        (vec![1 << 32, 1 << 32], "more than the 67108864 elements"),
        (vec![1 << 32, 1 << 32, -1], "more than the 67108864 elements"),
        (vec![1, 1 << 13, 1 << 13], "which cannot hold its input's 46 elements"),
        (vec![1, 47], "which cannot hold its input's 46 elements"),
        (vec![7, -1], "which cannot hold its input's 46 elements"),
        (vec![-1, -1], "more than one size to infer"),
        (vec![-2, -23], "a size below -1"),
    ] {
        let err = refused(&format!("reshape to {shape:?}"), &reshaped(&shape)).to_string();
        assert!(err.contains("operator \"Reshape\" has the shape") && err.contains(message), "{shape:?}: {err}");
    }
    // A constant reshaped to a shape that cannot hold it, and the shapes that can: the observation as [1, 46], [2, 23]
    // (batch 1 read as 2 × 23), [-1, 46], [0, 46] (0 copies the input's size) load.
    let nodes = vec![node("Reshape", &["c", "s"], "logits", vec![])];
    let weights = vec![floats("c", &[5], &[0.0; 5]), int64s("s", &[1, 6])];
    let err = refused("constant reshape", &model(nodes, weights)).to_string();
    assert!(err.contains("which cannot hold its input's 5 elements"), "{err}");
    for shape in [vec![1i64, 46], vec![2, 23], vec![-1, 46], vec![0, 46]] {
        Policy::from_bytes(&reshaped(&shape)).unwrap_or_else(|e| panic!("{shape:?}: {e}"));
    }
}

#[test]
fn values_that_multiply_to_terabytes_are_refused_before_they_are_made() {
    // Constants of 40 elements reshaped onto six distinct axes and added: tract computes such values while it
    // loads the graph (40^6 elements, 16 GB; 40^5 took 4 s and 400 MB before this was checked).
    let k = 40i64;
    let values: Vec<f32> = (0..k).map(|i| i as f32).collect();
    let mut nodes = vec![];
    let mut weights = vec![floats("c", &[k], &values)];
    for axis in 0..6 {
        let mut shape = vec![1i64; 6];
        shape[axis] = k;
        weights.push(int64s(&format!("s{axis}"), &shape));
        nodes.push(node("Reshape", &["c", &format!("s{axis}")], &format!("r{axis}"), vec![]));
    }
    nodes.push(node("Add", &["r0", "r1"], "a1", vec![]));
    for i in 2..6 {
        nodes.push(node("Add", &[&format!("a{}", i - 1), &format!("r{i}")], &format!("a{i}"), vec![]));
    }
    nodes.push(node("Add", &["obs", "a5"], "logits", vec![]));
    let err = refused("constant broadcast", &model(nodes, weights)).to_string();
    assert!(err.contains("its constants make values of more than 67108864 elements while it loads"), "{err}");

    // The observation broadcast against constants: refused on the typed graph, before anything runs.
    let mut nodes = vec![node("Reshape", &["obs", "s"], "x", vec![])];
    let mut weights = vec![floats("c", &[k], &values), int64s("s", &[1, 46, 1, 1, 1, 1])];
    for axis in 2..6 {
        let mut shape = vec![1i64; 6];
        shape[axis] = k;
        weights.push(int64s(&format!("s{axis}"), &shape));
        nodes.push(node("Reshape", &["c", &format!("s{axis}")], &format!("r{axis}"), vec![]));
    }
    nodes.push(node("Mul", &["x", "r2"], "m2", vec![]));
    for i in 3..6 {
        nodes.push(node("Mul", &[&format!("m{}", i - 1), &format!("r{i}")], &format!("m{i}"), vec![]));
    }
    nodes.push(node("Flatten", &["m5"], "logits", vec![]));
    let err = refused("observation broadcast", &model(nodes, weights)).to_string();
    assert!(err.contains("its values hold more than 67108864 elements for one observation"), "{err}");

    // A declared shape of 2^62 elements, and a tensor that claims more elements than the file holds.
    let mut m = ModelProto::decode(&*model(vec![node("Relu", &["obs"], "logits", vec![])], vec![])).unwrap();
    m.graph.as_mut().unwrap().value_info.push(value("logits", &[1 << 31, 1 << 31]));
    let err = refused("declared shape", &m.encode_to_vec()).to_string();
    assert!(err.contains("\"logits\" is declared larger than a policy's values may be"), "{err}");
    let big = TensorProto { name: "w".into(), dims: vec![1 << 20, 1 << 20], data_type: 1, ..Default::default() };
    let err = refused("tensor dims", &model(vec![node("Relu", &["obs"], "logits", vec![])], vec![big])).to_string();
    assert!(err.contains("more than the file holds"), "{err}");
}

#[test]
fn a_graph_that_costs_too_many_multiply_adds_is_refused() {
    // From the observation alone: [46, 1] × [1, 2048] → [46, 2048]; its transpose times itself → [2048, 2048];
    // that square times itself: 8.6 G multiply-adds for 12 Mi values.
    let nodes = vec![
        node("Reshape", &["obs", "s"], "col", vec![]),
        node("MatMul", &["col", "row"], "wide", vec![]),
        node("Transpose", &["wide"], "tall", vec![ints("perm", &[1, 0])]),
        node("MatMul", &["tall", "wide"], "square", vec![]),
        node("MatMul", &["square", "square"], "big", vec![]),
        node("Flatten", &["big"], "logits", vec![]),
    ];
    let weights = vec![int64s("s", &[46, 1]), floats("row", &[1, 2048], &[1.0; 2048])];
    let err = refused("matmul cost", &model(nodes, weights)).to_string();
    assert!(err.contains("it costs more than 1073741824 multiply-adds for one observation"), "{err}");
}

#[test]
fn a_convolution_that_costs_too_many_multiply_adds_is_refused() {
    // [46, 2048] from the observation (as above) as one 46 × 2048 image, convolved by 256 kernels of 8 × 64:
    // 20 Mi output values, 40 Mi unfolded patches, 10 G multiply-adds.
    let nodes = vec![
        node("Reshape", &["obs", "s"], "col", vec![]),
        node("MatMul", &["col", "row"], "wide", vec![]),
        node("Reshape", &["wide", "image_shape"], "image", vec![]),
        node("Conv", &["image", "w"], "conv", vec![ints("kernel_shape", &[8, 64])]),
        node("Flatten", &["conv"], "logits", vec![]),
    ];
    let weights = vec![
        int64s("s", &[46, 1]),
        floats("row", &[1, 2048], &[1.0; 2048]),
        int64s("image_shape", &[1, 1, 46, 2048]),
        floats("w", &[256, 1, 8, 64], &vec![0.5; 256 * 8 * 64]),
    ];
    let err = refused("conv cost", &model(nodes, weights)).to_string();
    assert!(err.contains("it costs more than 1073741824 multiply-adds for one observation (at \"conv"), "{err}");
}

#[test]
fn wide_and_long_graphs_are_refused_at_once() {
    let inputs = vec!["obs"; 2000];
    let concat = node("Concat", &inputs, "logits", vec![int("axis", 1)]);
    let err = refused("concat of 2000", &model(vec![concat], vec![])).to_string();
    assert!(err.contains("operator \"Concat\" has 2000 inputs"), "{err}");
    let err = refused("4000 relu", &relu_chain(4000)).to_string();
    assert!(err.contains("the graph has 4001 nodes, more than the 64"), "{err}");
}

#[test]
fn a_graph_at_the_node_limit_loads_fast() {
    let start = Instant::now();
    let mut policy = Policy::from_bytes(&relu_chain(chopperscape_policy::MAX_NODES - 1)).unwrap();
    let obs = chopperscape::Observation::zeros(vec![46], chopperscape::Dtype::F32);
    assert_eq!(policy.logits(&obs).unwrap(), [0.0; 5]);
    let took = start.elapsed();
    eprintln!("{} nodes loaded and run in {took:?}", chopperscape_policy::MAX_NODES);
    assert!(took < Duration::from_secs(2), "{took:?}");
}

#[test]
fn metadata_asking_for_huge_observations_is_refused_before_anything_is_allocated() {
    // rgb_float 4096 × 4096 stacked 4 deep: 1.9 GB of env buffers, which fit the env's 4 GiB budget.
    let bytes = with_metadata(&[
        ("obs_type", "rgb_float"),
        ("obs_shape", "[4096, 4096, 12]"),
        ("env_options", r#"{"obs_size": [4096, 4096], "frame_stack": 4}"#),
    ]);
    let err = refused("rgb_float 4096x4096x12", &bytes).to_string();
    assert!(err.contains("`obs_shape` is [4096, 4096, 12]: 201326592 elements, more than the 8388608"), "{err}");
    // The shape small, the options large: refused on the options, before the env is made.
    let bytes = with_metadata(&[
        ("obs_type", "rgb_float"),
        ("obs_shape", "[84, 84, 3]"),
        ("env_options", r#"{"obs_size": [4096, 4096]}"#),
    ]);
    let err = refused("rgb_float options", &bytes).to_string();
    assert!(err.contains("give rgb_float observations of 50331648 elements, more than the 8388608"), "{err}");
    // Every option at its most, and values that are no options: refused, one line each.
    for (key, value) in [
        ("env_options", r#"{"obs_size": [4096, 4096], "frame_stack": 64, "obs_type": "rgb_float"}"#),
        ("env_options", "{\"frame_skip\": 1e400}"),
        ("env_options", "{\"frame\\nskip\": 1}"),
        ("env_options", "{\"frame_skip\": \"4\\n\\u001b[31m\"}"),
        ("env_options", &format!("{{\"hud_style\": \"{}\"}}", "x".repeat(100_000))),
        ("env_options", &format!("{}{}", "[".repeat(10_000), "]".repeat(10_000))),
        ("obs_shape", &format!("[{}]", vec!["4096"; 100_000].join(","))),
        ("obs_shape", "[4096, 4096, 4096]"),
        ("obs_type", "rgb\n"),
        ("features_version", "99999999999999999999"),
        ("format", &"f".repeat(1 << 20)),
    ] {
        let err = refused(key, &with_metadata(&[(key, value)])).to_string();
        assert!(err.contains(&format!("`{key}`")), "{err}");
    }
}

#[test]
fn the_shape_arithmetic_of_older_torch_exports_passes_the_limits() {
    // `x.view(x.size(0), -1)` as the legacy exporter writes it: Shape, Gather, Unsqueeze, Concat, Reshape.
    let nodes = vec![
        node("Shape", &["obs"], "shape", vec![]),
        node("Gather", &["shape", "zero"], "batch", vec![int("axis", 0)]),
        node("Unsqueeze", &["batch", "axes"], "batch1", vec![]),
        node("Concat", &["batch1", "minus_one"], "target", vec![int("axis", 0)]),
        node("Reshape", &["obs", "target"], "flat", vec![]),
        node("Slice", &["flat", "starts", "ends", "last"], "logits", vec![]),
    ];
    let zero = TensorProto { name: "zero".into(), data_type: 7, int64_data: vec![0], ..Default::default() };
    let weights = vec![
        zero,
        int64s("axes", &[0]),
        int64s("minus_one", &[-1]),
        int64s("starts", &[0]),
        int64s("ends", &[5]),
        int64s("last", &[1]),
    ];
    let mut policy = Policy::from_bytes(&model(nodes, weights)).unwrap();
    let obs = chopperscape::Observation::zeros(vec![46], chopperscape::Dtype::F32);
    assert_eq!(policy.logits(&obs).unwrap(), [0.0; 5]);
}

#[test]
fn every_exported_model_passes_the_limits() {
    let models = concat!(env!("CARGO_MANIFEST_DIR"), "/../../models");
    let mut paths: Vec<_> = std::fs::read_dir(models)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "onnx"))
        .collect();
    paths.push(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/pixels-untrained.onnx").into());
    assert!(paths.len() >= 3, "{paths:?}");
    for path in paths {
        let start = Instant::now();
        let mut policy = Policy::load(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let meta = policy.metadata().clone();
        let config = policy.config().unwrap();
        policy.check(&config).unwrap();
        let mut env = chopperscape::ChopperScape::new(config).unwrap();
        let (obs, _) = chopperscape::Env::reset(&mut env, Some(0));
        assert!(policy.logits(&obs).unwrap().iter().all(|l| l.is_finite()));
        eprintln!(
            "{}: {} {:?} loaded and run in {:?}",
            path.display(),
            meta.obs_type.as_str(),
            meta.obs_shape,
            start.elapsed()
        );
    }
}
