//! Checks a glTF document's JSON before the `gltf` crate sees it: the crate indexes arrays
//! without bounds checks while validating (an accessor index past the end panics) and follows
//! node children recursively (a cycle overflows the stack). Every error names its JSON path.
//!
//! Checked: the JSON itself (for `.glb`, the header and the JSON chunk), glTF 1.0 and required
//! extensions (said plainly instead of as parser noise), every index into a top-level array,
//! byte ranges of buffer views and accessors against their buffers and views, and the node
//! hierarchy (no cycles, at most one parent per node).

use serde_json::{Map, Value};

/// The JSON text of a `.gltf` or `.glb` file, or what is wrong with the GLB container.
pub fn json_of(bytes: &[u8]) -> Result<&[u8], String> {
    if !bytes.starts_with(b"glTF") {
        return Ok(bytes);
    }
    let word = |at: usize| -> Option<u32> {
        bytes
            .get(at..at + 4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    };
    let version = word(4).ok_or("GLB: truncated header")?;
    if version != 2 {
        return Err(format!(
            "GLB version {version}: only glTF 2.0 (GLB version 2) is supported"
        ));
    }
    let length = word(12).ok_or("GLB: truncated chunk header")? as usize;
    if word(16) != Some(0x4E4F_534A) {
        return Err("GLB: the first chunk is not JSON".into());
    }
    bytes
        .get(20..20usize.saturating_add(length))
        .ok_or_else(|| format!("GLB: the JSON chunk says {length} bytes but the file ends first"))
}

/// Checks the document; the error names the JSON path of the first problem.
pub fn check(json: &[u8]) -> Result<(), String> {
    let root: Value = serde_json::from_slice(json).map_err(|e| format!("not valid JSON: {e}"))?;
    let Some(root) = root.as_object() else {
        return Err("the top level is not a JSON object".into());
    };
    version(root)?;
    required_extensions(root)?;
    top_level_arrays(root)?;
    let doc = Document::new(root);
    scene_and_node_indices(&doc)?;
    mesh_indices(&doc)?;
    material_texture_and_image_indices(&doc)?;
    skin_and_animation_indices(&doc)?;
    buffer_view_and_accessor_indices(&doc)?;
    byte_ranges(
        doc.array("buffers"),
        doc.array("bufferViews"),
        doc.array("accessors"),
    )?;
    node_hierarchy(doc.array("nodes"))
}

/// `asset.version` says glTF 2 (glTF 1.0 and other versions said plainly).
fn version(root: &Map<String, Value>) -> Result<(), String> {
    let version = root
        .get("asset")
        .and_then(|a| a.get("version"))
        .and_then(Value::as_str);
    let old_style = ["meshes", "nodes", "accessors"]
        .iter()
        .any(|k| root.get(*k).is_some_and(Value::is_object));
    match version {
        Some(v) if v.starts_with('2') => Ok(()),
        Some(v) => Err(format!("asset.version is \"{v}\": glTF {v} is not supported, only glTF 2.0 (convert the file, e.g. with Blender or gltf-pipeline)")),
        None if old_style => Err("glTF 1.0 is not supported, only glTF 2.0 (this file has no asset.version and uses 1.0's named objects)".into()),
        None => Err("asset.version: missing (glTF 2.0 files say \"2.0\")".into()),
    }
}

/// Every extension in `extensionsRequired` is one specula reads.
fn required_extensions(root: &Map<String, Value>) -> Result<(), String> {
    if let Some(required) = root.get("extensionsRequired").and_then(Value::as_array) {
        for (i, e) in required.iter().enumerate() {
            let name = e.as_str().unwrap_or("?");
            if !super::gltf_file::SUPPORTED_EXTENSIONS.contains(&name) {
                return Err(format!(
                    "extensionsRequired[{i}]: the file requires {name}, which specula does not support"
                ));
            }
        }
    }
    Ok(())
}

/// The top-level collections, where present, are arrays.
fn top_level_arrays(root: &Map<String, Value>) -> Result<(), String> {
    for key in [
        "scenes",
        "nodes",
        "meshes",
        "accessors",
        "bufferViews",
        "buffers",
        "materials",
        "textures",
        "images",
        "samplers",
        "cameras",
        "skins",
        "animations",
    ] {
        if root.get(key).is_some_and(|v| !v.is_array()) {
            return Err(format!("{key}: expected an array"));
        }
    }
    Ok(())
}

/// The document's top level: its arrays, and the counts indices into them are checked
/// against.
struct Document<'a> {
    root: &'a Map<String, Value>,
    /// Lights of `KHR_lights_punctual`.
    lights: usize,
}

impl<'a> Document<'a> {
    fn new(root: &'a Map<String, Value>) -> Document<'a> {
        let lights = root
            .get("extensions")
            .and_then(|e| e.get("KHR_lights_punctual"))
            .and_then(|e| e.get("lights"))
            .and_then(Value::as_array)
            .map_or(0, Vec::len);
        Document { root, lights }
    }

    /// Entries of the top-level array `key` (0 when it is absent).
    fn len(&self, key: &str) -> usize {
        self.array(key).len()
    }

    /// The top-level array `key` (empty when it is absent).
    fn array(&self, key: &str) -> &'a [Value] {
        self.root
            .get(key)
            .and_then(Value::as_array)
            .map_or(&[], Vec::as_slice)
    }
}

/// The default scene, each scene's nodes, and each node's children, mesh, camera, skin and
/// light.
fn scene_and_node_indices(doc: &Document) -> Result<(), String> {
    index(doc.root.get("scene"), "scene", doc.len("scenes"))?;
    for (s, scene) in doc.array("scenes").iter().enumerate() {
        indices(
            scene.get("nodes"),
            &format!("scenes[{s}].nodes"),
            doc.len("nodes"),
        )?;
    }
    for (n, node) in doc.array("nodes").iter().enumerate() {
        let at = |what: &str| format!("nodes[{n}].{what}");
        indices(node.get("children"), &at("children"), doc.len("nodes"))?;
        index(node.get("mesh"), &at("mesh"), doc.len("meshes"))?;
        index(node.get("camera"), &at("camera"), doc.len("cameras"))?;
        index(node.get("skin"), &at("skin"), doc.len("skins"))?;
        let light = node
            .get("extensions")
            .and_then(|e| e.get("KHR_lights_punctual"))
            .and_then(|e| e.get("light"));
        index(
            light,
            &at("extensions.KHR_lights_punctual.light"),
            doc.lights,
        )?;
    }
    Ok(())
}

/// Each primitive's attribute, index, morph-target and material references, and its
/// attributes' accessor types.
fn mesh_indices(doc: &Document) -> Result<(), String> {
    let accessors = doc.len("accessors");
    for (m, mesh) in doc.array("meshes").iter().enumerate() {
        let primitives = mesh.get("primitives").and_then(Value::as_array);
        for (p, primitive) in primitives.map_or(&[][..], Vec::as_slice).iter().enumerate() {
            let at = |what: &str| format!("meshes[{m}].primitives[{p}].{what}");
            if let Some(attributes) = primitive.get("attributes").and_then(Value::as_object) {
                for (name, value) in attributes {
                    index(Some(value), &at(&format!("attributes.{name}")), accessors)?;
                }
            }
            index(primitive.get("indices"), &at("indices"), accessors)?;
            attribute_types(primitive, doc.array("accessors"), &at)?;
            index(
                primitive.get("material"),
                &at("material"),
                doc.len("materials"),
            )?;
            let targets = primitive.get("targets").and_then(Value::as_array);
            for (t, target) in targets.map_or(&[][..], Vec::as_slice).iter().enumerate() {
                for (name, value) in target.as_object().into_iter().flatten() {
                    index(Some(value), &at(&format!("targets[{t}].{name}")), accessors)?;
                }
            }
        }
    }
    Ok(())
}

/// The materials' texture references, each texture's image and sampler, and each image's
/// buffer view (an image has exactly one of a URI and a buffer view with a MIME type).
fn material_texture_and_image_indices(doc: &Document) -> Result<(), String> {
    for (m, material) in doc.array("materials").iter().enumerate() {
        texture_references(material, &format!("materials[{m}]"), doc.len("textures"))?;
    }
    for (t, texture) in doc.array("textures").iter().enumerate() {
        index(
            texture.get("source"),
            &format!("textures[{t}].source"),
            doc.len("images"),
        )?;
        index(
            texture.get("sampler"),
            &format!("textures[{t}].sampler"),
            doc.len("samplers"),
        )?;
    }
    for (i, image) in doc.array("images").iter().enumerate() {
        index(
            image.get("bufferView"),
            &format!("images[{i}].bufferView"),
            doc.len("bufferViews"),
        )?;
        match (image.get("uri"), image.get("bufferView")) {
            (Some(_), None) => {}
            (None, Some(_)) if image.get("mimeType").is_some_and(Value::is_string) => {}
            (None, Some(_)) => {
                return Err(format!("images[{i}].mimeType: required with a bufferView"))
            }
            _ => {
                return Err(format!(
                    "images[{i}]: give exactly one of uri and bufferView"
                ))
            }
        }
    }
    Ok(())
}

/// Each skin's joints, skeleton and inverse bind matrices; each animation's samplers'
/// accessors and its channels' samplers and target nodes.
fn skin_and_animation_indices(doc: &Document) -> Result<(), String> {
    for (s, skin) in doc.array("skins").iter().enumerate() {
        indices(
            skin.get("joints"),
            &format!("skins[{s}].joints"),
            doc.len("nodes"),
        )?;
        index(
            skin.get("skeleton"),
            &format!("skins[{s}].skeleton"),
            doc.len("nodes"),
        )?;
        index(
            skin.get("inverseBindMatrices"),
            &format!("skins[{s}].inverseBindMatrices"),
            doc.len("accessors"),
        )?;
    }
    for (a, animation) in doc.array("animations").iter().enumerate() {
        let samplers = animation.get("samplers").and_then(Value::as_array);
        let sampler_count = samplers.map_or(0, Vec::len);
        for (s, sampler) in samplers.map_or(&[][..], Vec::as_slice).iter().enumerate() {
            let at = format!("animations[{a}].samplers[{s}]");
            index(
                sampler.get("input"),
                &format!("{at}.input"),
                doc.len("accessors"),
            )?;
            index(
                sampler.get("output"),
                &format!("{at}.output"),
                doc.len("accessors"),
            )?;
        }
        let channels = animation.get("channels").and_then(Value::as_array);
        for (c, channel) in channels.map_or(&[][..], Vec::as_slice).iter().enumerate() {
            let at = format!("animations[{a}].channels[{c}]");
            index(
                channel.get("sampler"),
                &format!("{at}.sampler"),
                sampler_count,
            )?;
            let node = channel.get("target").and_then(|t| t.get("node"));
            index(node, &format!("{at}.target.node"), doc.len("nodes"))?;
        }
    }
    Ok(())
}

/// Each buffer view's buffer (required), each accessor's buffer view and its sparse parts'.
fn buffer_view_and_accessor_indices(doc: &Document) -> Result<(), String> {
    for (v, view) in doc.array("bufferViews").iter().enumerate() {
        let path = format!("bufferViews[{v}].buffer");
        let buffer = view
            .get("buffer")
            .ok_or_else(|| format!("{path}: missing"))?;
        index(Some(buffer), &path, doc.len("buffers"))?;
    }
    for (a, accessor) in doc.array("accessors").iter().enumerate() {
        let at = |what: &str| format!("accessors[{a}].{what}");
        index(
            accessor.get("bufferView"),
            &at("bufferView"),
            doc.len("bufferViews"),
        )?;
        if let Some(sparse) = accessor.get("sparse") {
            for part in ["indices", "values"] {
                let view = sparse.get(part).and_then(|p| p.get("bufferView"));
                index(
                    view,
                    &at(&format!("sparse.{part}.bufferView")),
                    doc.len("bufferViews"),
                )?;
            }
        }
    }
    Ok(())
}

/// The accessor types the glTF spec allows for each vertex attribute a primitive names (the
/// gltf crate asserts them when reading, so a mismatch would panic there).
fn attribute_types(
    primitive: &Value,
    accessors: &[Value],
    at: &dyn Fn(&str) -> String,
) -> Result<(), String> {
    const FLOAT: u64 = 5126;
    const UBYTE: u64 = 5121;
    const USHORT: u64 = 5123;
    const UINT: u64 = 5125;
    let allowed = |semantic: &str| -> Option<(&[&str], &[u64])> {
        let base = semantic.split('_').next().unwrap_or(semantic);
        Some(match (semantic, base) {
            ("POSITION" | "NORMAL", _) => (&["VEC3"], &[FLOAT]),
            ("TANGENT", _) => (&["VEC4"], &[FLOAT]),
            (_, "TEXCOORD") => (&["VEC2"], &[FLOAT, UBYTE, USHORT]),
            (_, "COLOR") => (&["VEC3", "VEC4"], &[FLOAT, UBYTE, USHORT]),
            (_, "JOINTS") => (&["VEC4"], &[UBYTE, USHORT]),
            (_, "WEIGHTS") => (&["VEC4"], &[FLOAT, UBYTE, USHORT]),
            _ => return None,
        })
    };
    let check = |path: String, accessor: Option<&Value>, types: &[&str], components: &[u64]| {
        let Some(accessor) = accessor
            .and_then(|a| a.as_u64())
            .and_then(|a| accessors.get(a as usize))
        else {
            return Ok(());
        };
        let ty = accessor.get("type").and_then(Value::as_str).unwrap_or("?");
        let component = number(accessor, "componentType").unwrap_or(0);
        if types.contains(&ty) && components.contains(&component) {
            Ok(())
        } else {
            Err(format!(
                "{path}: an accessor of type {ty} with componentType {component}, but this attribute takes {} of componentType {}",
                types.join(" or "),
                components.iter().map(u64::to_string).collect::<Vec<_>>().join(", ")
            ))
        }
    };
    for (name, value) in primitive
        .get("attributes")
        .and_then(Value::as_object)
        .into_iter()
        .flatten()
    {
        if let Some((types, components)) = allowed(name) {
            check(
                at(&format!("attributes.{name}")),
                Some(value),
                types,
                components,
            )?;
        }
    }
    check(
        at("indices"),
        primitive.get("indices"),
        &["SCALAR"],
        &[UBYTE, USHORT, UINT],
    )
}

/// `value`, when present, must be a whole number below `count`.
fn index(value: Option<&Value>, path: &str, count: usize) -> Result<(), String> {
    let Some(value) = value else {
        return Ok(());
    };
    match value.as_u64() {
        Some(i) if (i as usize) < count && i <= u32::MAX as u64 => Ok(()),
        Some(i) => Err(format!(
            "{path}: index {i} is out of range (there are {count})"
        )),
        None => Err(format!(
            "{path}: expected an index (a whole number ≥ 0), got {value}"
        )),
    }
}

fn indices(value: Option<&Value>, path: &str, count: usize) -> Result<(), String> {
    let Some(value) = value else {
        return Ok(());
    };
    let list = value
        .as_array()
        .ok_or_else(|| format!("{path}: expected an array of indices"))?;
    list.iter()
        .enumerate()
        .try_for_each(|(i, v)| index(Some(v), &format!("{path}[{i}]"), count))
}

/// Every `{"index": n}` texture reference inside a material, at any depth (core textures and
/// the extensions' alike).
fn texture_references(value: &Value, path: &str, textures: usize) -> Result<(), String> {
    match value {
        Value::Object(map) => {
            for (key, child) in map {
                let child_path = format!("{path}.{key}");
                if key == "index" && path.ends_with("Texture") {
                    index(Some(child), &child_path, textures)?;
                } else {
                    texture_references(child, &child_path, textures)?;
                }
            }
            Ok(())
        }
        Value::Array(items) => items
            .iter()
            .enumerate()
            .try_for_each(|(i, v)| texture_references(v, &format!("{path}[{i}]"), textures)),
        _ => Ok(()),
    }
}

fn number(value: &Value, key: &str) -> Option<u64> {
    value.get(key).and_then(Value::as_u64)
}

/// Buffer views lie inside their buffers, accessors inside their views.
fn byte_ranges(buffers: &[Value], views: &[Value], accessors: &[Value]) -> Result<(), String> {
    for (v, view) in views.iter().enumerate() {
        let buffer = number(view, "buffer").unwrap_or(0) as usize;
        let buffer_length = buffers.get(buffer).and_then(|b| number(b, "byteLength"));
        let offset = number(view, "byteOffset").unwrap_or(0);
        let length = number(view, "byteLength")
            .ok_or_else(|| format!("bufferViews[{v}].byteLength: missing or not a whole number"))?;
        if let Some(buffer_length) = buffer_length {
            if offset
                .checked_add(length)
                .is_none_or(|end| end > buffer_length)
            {
                return Err(format!(
                    "bufferViews[{v}]: bytes {offset}..{} run past buffers[{buffer}] ({buffer_length} bytes)",
                    offset.saturating_add(length)
                ));
            }
        }
        if let Some(stride) = view.get("byteStride") {
            if !stride
                .as_u64()
                .is_some_and(|s| (4..=252).contains(&s) && s % 4 == 0)
            {
                return Err(format!(
                    "bufferViews[{v}].byteStride: {stride} is not a multiple of 4 from 4 to 252"
                ));
            }
        }
    }
    for (a, accessor) in accessors.iter().enumerate() {
        let at = |what: &str| format!("accessors[{a}].{what}");
        let component = match number(accessor, "componentType") {
            Some(5120 | 5121) => 1,
            Some(5122 | 5123) => 2,
            Some(5125 | 5126) => 4,
            other => {
                return Err(format!(
                    "{}: {} is not a glTF component type",
                    at("componentType"),
                    other.map_or("missing".to_string(), |o| o.to_string())
                ))
            }
        };
        let components = match accessor.get("type").and_then(Value::as_str) {
            Some("SCALAR") => 1,
            Some("VEC2") => 2,
            Some("VEC3") => 3,
            Some("VEC4" | "MAT2") => 4,
            Some("MAT3") => 9,
            Some("MAT4") => 16,
            other => {
                return Err(format!(
                    "{}: {other:?} is not a glTF accessor type",
                    at("type")
                ))
            }
        };
        let count = number(accessor, "count")
            .ok_or_else(|| format!("{}: missing or not a whole number", at("count")))?;
        let Some(view_index) = number(accessor, "bufferView") else {
            continue;
        };
        let view = &views[view_index as usize];
        let view_length = number(view, "byteLength").unwrap_or(0);
        let element = component * components;
        let stride = number(view, "byteStride").unwrap_or(element);
        if stride < element {
            return Err(format!(
                "accessors[{a}]: elements of {element} bytes in bufferViews[{view_index}] whose byteStride is {stride}"
            ));
        }
        let offset = number(accessor, "byteOffset").unwrap_or(0);
        let needed = count
            .checked_sub(1)
            .map(|last| {
                last.checked_mul(stride)
                    .and_then(|b| b.checked_add(element))
                    .and_then(|b| b.checked_add(offset))
            })
            .unwrap_or(Some(offset));
        if needed.is_none_or(|n| n > view_length) {
            return Err(format!(
                "accessors[{a}]: {count} elements of {element} bytes (stride {stride}, offset {offset}) run past bufferViews[{view_index}] ({view_length} bytes)"
            ));
        }
    }
    Ok(())
}

/// No node is its own descendant and none has two parents (glTF requires a forest; the crate
/// would recurse forever on a cycle).
fn node_hierarchy(nodes: &[Value]) -> Result<(), String> {
    let children = |n: usize| -> Vec<usize> {
        nodes[n]
            .get("children")
            .and_then(Value::as_array)
            .map(|c| {
                c.iter()
                    .filter_map(|v| v.as_u64())
                    .map(|v| v as usize)
                    .collect()
            })
            .unwrap_or_default()
    };
    let mut parent: Vec<Option<usize>> = vec![None; nodes.len()];
    for n in 0..nodes.len() {
        for c in children(n) {
            if let Some(p) = parent[c] {
                return Err(format!(
                    "nodes[{c}]: a child of both nodes[{p}] and nodes[{n}] (a node may have one parent)"
                ));
            }
            parent[c] = Some(n);
        }
    }
    // With one parent each, a cycle is a walk up the parents that returns to its start.
    for start in 0..nodes.len() {
        let mut at = start;
        for _ in 0..=nodes.len() {
            match parent[at] {
                Some(p) if p == start => {
                    return Err(format!("nodes[{start}]: the node is among its own descendants (a cycle in the node hierarchy)"))
                }
                Some(p) => at = p,
                None => break,
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn error(json: &str) -> String {
        check(json.as_bytes()).unwrap_err()
    }

    #[test]
    fn bad_indices_cycles_and_versions_name_the_path() {
        let cases = [
            (
                r#"{"asset":{"version":"2.0"},"meshes":[{"primitives":[{"attributes":{"POSITION":7}}]}]}"#,
                "meshes[0].primitives[0].attributes.POSITION: index 7 is out of range (there are 0)",
            ),
            (
                r#"{"asset":{"version":"2.0"},"nodes":[{"children":[1]},{"children":[0]}]}"#,
                "among its own descendants",
            ),
            (
                r#"{"asset":{"version":"2.0"},"nodes":[{"children":[0]}]}"#,
                "nodes[0]: the node is among its own descendants",
            ),
            (
                r#"{"asset":{"version":"2.0"},"nodes":[{"children":[2]},{"children":[2]},{}]}"#,
                "nodes[2]: a child of both",
            ),
            (r#"{"asset":{"version":"1.0"},"meshes":{}}"#, "glTF 1.0 is not supported"),
            (r#"{"meshes":{"m":{}}}"#, "glTF 1.0 is not supported"),
            (
                r#"{"asset":{"version":"2.0"},"extensionsRequired":["KHR_draco_mesh_compression"]}"#,
                "requires KHR_draco_mesh_compression",
            ),
            (
                r#"{"asset":{"version":"2.0"},"buffers":[{"byteLength":8}],"bufferViews":[{"buffer":0,"byteOffset":4,"byteLength":8}]}"#,
                "bufferViews[0]: bytes 4..12 run past buffers[0] (8 bytes)",
            ),
            (
                r#"{"asset":{"version":"2.0"},"buffers":[{"byteLength":36}],"bufferViews":[{"buffer":0,"byteLength":36}],"accessors":[{"bufferView":0,"componentType":5126,"type":"VEC3","count":4}]}"#,
                "accessors[0]: 4 elements of 12 bytes",
            ),
            (
                r#"{"asset":{"version":"2.0"},"materials":[{"pbrMetallicRoughness":{"baseColorTexture":{"index":3}}}]}"#,
                "materials[0].pbrMetallicRoughness.baseColorTexture.index: index 3 is out of range",
            ),
            (r#"{"asset":{"version":"2.0"},"scene":-1}"#, "scene: expected an index"),
            (r#"{"asset":{"version":"2.0"},"images":[{}]}"#, "images[0]: give exactly one of uri and bufferView"),
            (
                r#"{"asset":{"version":"2.0"},"accessors":[{"componentType":5126,"type":"VEC2","count":1}],"meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}]}"#,
                "meshes[0].primitives[0].attributes.POSITION: an accessor of type VEC2",
            ),
            (
                r#"{"asset":{"version":"2.0"},"buffers":[{"byteLength":4}],"bufferViews":[{"buffer":0,"byteLength":4}],"images":[{"bufferView":0}]}"#,
                "images[0].mimeType: required with a bufferView",
            ),
            ("[1, 2]", "not a JSON object"),
            ("{", "not valid JSON"),
        ];
        for (json, expected) in cases {
            let message = error(json);
            assert!(
                message.contains(expected),
                "{json}: {message:?} should say {expected:?}"
            );
        }
    }

    #[test]
    fn a_valid_document_passes() {
        let json = r#"{"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],
            "nodes":[{"children":[1],"mesh":0},{}],
            "buffers":[{"byteLength":36}],"bufferViews":[{"buffer":0,"byteLength":36}],
            "accessors":[{"bufferView":0,"componentType":5126,"type":"VEC3","count":3}],
            "meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}]}"#;
        check(json.as_bytes()).unwrap();
    }

    #[test]
    fn glb_containers_are_checked() {
        assert!(json_of(b"glTF\x02\x00\x00\x00")
            .unwrap_err()
            .contains("truncated"));
        let mut glb = b"glTF".to_vec();
        glb.extend(2u32.to_le_bytes());
        glb.extend(100u32.to_le_bytes());
        glb.extend(50u32.to_le_bytes());
        glb.extend(0x4E4F_534Au32.to_le_bytes());
        glb.extend(b"{}");
        assert!(json_of(&glb).unwrap_err().contains("50 bytes"));
        assert_eq!(json_of(b"{\"asset\":1}").unwrap(), b"{\"asset\":1}");
    }
}
