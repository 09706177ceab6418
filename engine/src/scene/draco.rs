//! KHR_draco_mesh_compression: a primitive's indices and attributes come from a Draco bitstream instead of
//! its accessors. Decoded with `draco-oxide-decoder`, a pure-Rust decoder of Draco's mesh bitstream 2.2
//! (the choice is explained in docs/GLTF.md). Failures are messages, never panics: the decoder runs under
//! `catch_unwind`, and every count and index it returns is checked before use.

use super::accessor::Floats;
use std::collections::HashMap;

pub(super) const EXTENSION: &str = "KHR_draco_mesh_compression";

/// A decoded Draco primitive: triangle corner indices and each glTF attribute's per-vertex values.
#[derive(Debug)]
pub(super) struct DracoPrimitive {
    pub indices: Vec<u32>,
    pub vertex_count: usize,
    /// Keyed by the glTF attribute name (POSITION, NORMAL, TEXCOORD_0, JOINTS_0, ...).
    attributes: HashMap<String, DecodedAttribute>,
}

#[derive(Debug)]
struct DecodedAttribute {
    /// Component values as stored (integers unconverted), `dims` per vertex.
    values: Vec<f64>,
    dims: usize,
    /// Integer components (normalized accessors divide these by the type's maximum).
    component: draco_component::Type,
}

impl DracoPrimitive {
    /// The attribute as the glTF accessor describes it: normalized integer types map to [0, 1] / [-1, 1].
    pub fn floats(&self, name: &str, accessor: &gltf::Accessor) -> Option<Floats> {
        let a = self.attributes.get(name)?;
        let scale = match (accessor.normalized(), a.component) {
            (true, draco_component::Type::Integer { max }) => Some(max),
            _ => None,
        };
        let values = a
            .values
            .iter()
            .map(|&v| match scale {
                Some(max) => (v / max).max(-1.0) as f32,
                None => v as f32,
            })
            .collect();
        Some(Floats {
            values,
            dims: a.dims,
        })
    }

    pub fn has(&self, name: &str) -> bool {
        self.attributes.contains_key(name)
    }
}

mod draco_component {
    #[derive(Clone, Copy, Debug)]
    pub enum Type {
        Float,
        /// An integer type with this largest positive value (127, 255, 32767 ...).
        Integer {
            max: f64,
        },
    }
}

/// Decodes the Draco bitstream of `primitive`; `buffers` are the file's buffers.
pub(super) fn decode(
    primitive: &gltf::Primitive,
    extension: &serde_json::Value,
    document: &gltf::Document,
    buffers: &[Vec<u8>],
) -> Result<DracoPrimitive, String> {
    let view_index = extension
        .get("bufferView")
        .and_then(serde_json::Value::as_u64)
        .ok_or("its KHR_draco_mesh_compression extension has no bufferView")?
        as usize;
    let view = document.views().nth(view_index).ok_or_else(|| {
        format!("KHR_draco_mesh_compression names bufferView {view_index}, which does not exist")
    })?;
    let bytes = buffers
        .get(view.buffer().index())
        .and_then(|b| b.get(view.offset()..view.offset().checked_add(view.length())?))
        .ok_or_else(|| format!("Draco bufferView {view_index} lies outside its buffer"))?;
    let ids: Vec<(String, usize)> = extension
        .get("attributes")
        .and_then(serde_json::Value::as_object)
        .ok_or("its KHR_draco_mesh_compression extension has no attributes")?
        .iter()
        .map(|(name, id)| {
            id.as_u64()
                .map(|id| (name.clone(), id as usize))
                .ok_or_else(|| format!("Draco attribute id of {name} is not an integer"))
        })
        .collect::<Result<_, _>>()?;
    let decoded = decode_bitstream(bytes, &ids).map_err(|e| {
        format!("KHR_draco_mesh_compression data in bufferView {view_index} cannot be decoded: {e}")
    })?;
    // The decoded mesh replaces the accessors, so their counts must agree with it.
    for (name, _) in &ids {
        let accessor = primitive
            .attributes()
            .find(|(s, _)| s.to_string() == *name)
            .map(|(_, a)| a);
        if let Some(a) = accessor
            && a.count() != decoded.vertex_count
        {
            return Err(format!(
                "Draco data decodes {} vertices but the {name} accessor says {}",
                decoded.vertex_count,
                a.count()
            ));
        }
    }
    Ok(decoded)
}

/// Decodes a Draco mesh bitstream; `ids` maps glTF attribute names to Draco attribute unique ids.
pub(super) fn decode_bitstream(
    bytes: &[u8],
    ids: &[(String, usize)],
) -> Result<DracoPrimitive, String> {
    let mesh = std::panic::catch_unwind(|| draco_oxide_decoder::decode_mesh(bytes))
        .map_err(|_| "the Draco decoder failed on malformed data".to_string())?
        .map_err(|e| e.to_string())?;
    let vertex_count = mesh.attributes.iter().map(|a| a.len()).max().unwrap_or(0);
    let mut indices = Vec::with_capacity(mesh.faces.len() * 3);
    for face in &mesh.faces {
        for &p in face {
            let p = usize::from(p);
            if p >= vertex_count {
                return Err(format!("a decoded face names point {p} of {vertex_count}"));
            }
            indices.push(p as u32);
        }
    }
    let mut attributes = HashMap::new();
    for (name, id) in ids {
        let attribute = mesh
            .attributes
            .iter()
            .find(|a| a.get_id().as_usize() == *id)
            .ok_or_else(|| format!("the bitstream has no attribute with id {id} ({name})"))?;
        if attribute.len() != vertex_count {
            return Err(format!(
                "attribute {name} has {} values for {vertex_count} points",
                attribute.len()
            ));
        }
        let dims = attribute.get_num_components();
        let type_id = attribute.get_component_type().get_id();
        let (size, component) = component_layout(type_id)
            .ok_or_else(|| format!("attribute {name} has an unsupported component type"))?;
        let unique = attribute.get_data_as_bytes();
        let value_size = size * dims;
        if dims == 0 || dims > 4 || unique.len() % value_size != 0 {
            return Err(format!("attribute {name} has {dims} components"));
        }
        let unique_count = unique.len() / value_size;
        let map = attribute.point_map_as_slice();
        let mut values = Vec::with_capacity(vertex_count * dims);
        for point in 0..vertex_count {
            let v = match map {
                Some(map) => usize::from(map[point]),
                None => point,
            };
            if v >= unique_count {
                return Err(format!(
                    "attribute {name} maps a point to value {v} of {unique_count}"
                ));
            }
            for c in 0..dims {
                values.push(read_component(
                    &unique[v * value_size + c * size..],
                    type_id,
                ));
            }
        }
        attributes.insert(
            name.clone(),
            DecodedAttribute {
                values,
                dims,
                component,
            },
        );
    }
    Ok(DracoPrimitive {
        indices,
        vertex_count,
        attributes,
    })
}

/// Byte size and kind of a Draco component type, by its wire id (1 = i8 ... 6 = u32, 9 = f32).
fn component_layout(type_id: u8) -> Option<(usize, draco_component::Type)> {
    use draco_component::Type::{Float, Integer};
    Some(match type_id {
        1 => (1, Integer { max: 127.0 }),
        2 => (1, Integer { max: 255.0 }),
        3 => (2, Integer { max: 32767.0 }),
        4 => (2, Integer { max: 65535.0 }),
        5 => (
            4,
            Integer {
                max: i32::MAX as f64,
            },
        ),
        6 => (
            4,
            Integer {
                max: u32::MAX as f64,
            },
        ),
        9 => (4, Float),
        _ => return None,
    })
}

fn read_component(b: &[u8], type_id: u8) -> f64 {
    match type_id {
        1 => b[0] as i8 as f64,
        2 => b[0] as f64,
        3 => i16::from_le_bytes([b[0], b[1]]) as f64,
        4 => u16::from_le_bytes([b[0], b[1]]) as f64,
        5 => i32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
        6 => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
        _ => f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
    }
}
