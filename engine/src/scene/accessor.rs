//! Reading glTF accessors ourselves: every component type a vertex attribute may have under
//! KHR_mesh_quantization (normalized and unnormalized integers as well as floats), byte strides, sparse
//! substitution and accessors without a bufferView (zeros). Every read is bounds-checked, so a malformed file
//! gives an error message instead of a panic inside a reader that assumes float data.

use gltf::accessor::{DataType, Dimensions};

/// An accessor's elements as f32, `dims` values per element.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Floats {
    pub values: Vec<f32>,
    pub dims: usize,
}

impl Floats {
    /// The elements as fixed-size arrays; `N` must equal `dims`.
    pub fn to_arrays<const N: usize>(&self) -> Vec<[f32; N]> {
        debug_assert_eq!(N, self.dims);
        self.values
            .chunks_exact(N)
            .map(|c| std::array::from_fn(|i| c[i]))
            .collect()
    }
}

/// Component size in bytes.
pub(super) fn component_size(t: DataType) -> usize {
    match t {
        DataType::I8 | DataType::U8 => 1,
        DataType::I16 | DataType::U16 => 2,
        DataType::U32 | DataType::F32 => 4,
    }
}

fn dimension_count(d: Dimensions) -> Option<usize> {
    match d {
        Dimensions::Scalar => Some(1),
        Dimensions::Vec2 => Some(2),
        Dimensions::Vec3 => Some(3),
        Dimensions::Vec4 => Some(4),
        // Matrices have column padding for small components; no vertex attribute uses them.
        Dimensions::Mat2 | Dimensions::Mat3 | Dimensions::Mat4 => None,
    }
}

/// One component at `bytes[0..size]`, converted as glTF says: normalized integers map to [0, 1] or [-1, 1]
/// (`max(c / 127, -1)` for bytes, `max(c / 32767, -1)` for shorts), others keep their integer value.
pub(super) fn component_to_f32(bytes: &[u8], t: DataType, normalized: bool) -> f32 {
    match (t, normalized) {
        (DataType::I8, false) => bytes[0] as i8 as f32,
        (DataType::I8, true) => (bytes[0] as i8 as f32 / 127.0).max(-1.0),
        (DataType::U8, false) => bytes[0] as f32,
        (DataType::U8, true) => bytes[0] as f32 / 255.0,
        (DataType::I16, n) => {
            let v = i16::from_le_bytes([bytes[0], bytes[1]]) as f32;
            if n { (v / 32767.0).max(-1.0) } else { v }
        }
        (DataType::U16, n) => {
            let v = u16::from_le_bytes([bytes[0], bytes[1]]) as f32;
            if n { v / 65535.0 } else { v }
        }
        (DataType::U32, n) => {
            let v = u32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]]) as f32;
            if n { v / u32::MAX as f32 } else { v }
        }
        (DataType::F32, _) => f32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]]),
    }
}

fn type_name(t: DataType) -> &'static str {
    match t {
        DataType::I8 => "BYTE",
        DataType::U8 => "UNSIGNED_BYTE",
        DataType::I16 => "SHORT",
        DataType::U16 => "UNSIGNED_SHORT",
        DataType::U32 => "UNSIGNED_INT",
        DataType::F32 => "FLOAT",
    }
}

/// The bytes of one bufferView, checked against its buffer.
fn view_bytes<'b>(view: &gltf::buffer::View, buffers: &'b [Vec<u8>]) -> Result<&'b [u8], String> {
    let buffer = buffers
        .get(view.buffer().index())
        .ok_or_else(|| format!("bufferView {} names a missing buffer", view.index()))?;
    view.offset()
        .checked_add(view.length())
        .and_then(|end| buffer.get(view.offset()..end))
        .ok_or_else(|| {
            format!(
                "bufferView {} lies outside buffer {}",
                view.index(),
                view.buffer().index()
            )
        })
}

/// Reads `count` elements of `width` bytes starting at `offset` with `stride` from a view's bytes.
fn strided(
    bytes: &[u8],
    offset: usize,
    stride: usize,
    width: usize,
    count: usize,
) -> Option<impl Iterator<Item = &[u8]>> {
    if count > 0 {
        let last = stride.checked_mul(count - 1)?.checked_add(offset)?;
        if last.checked_add(width)? > bytes.len() {
            return None;
        }
    }
    Some((0..count).map(move |i| &bytes[offset + i * stride..][..width]))
}

/// Reads a scalar or vector accessor as f32 values, whatever its component type, with sparse values applied.
/// `what` names the attribute in messages.
pub(super) fn read_floats(
    accessor: &gltf::Accessor,
    buffers: &[Vec<u8>],
    what: &str,
) -> Result<Floats, String> {
    let t = accessor.data_type();
    let dims = dimension_count(accessor.dimensions())
        .ok_or_else(|| format!("{what} accessor {} is a matrix", accessor.index()))?;
    let normalized = accessor.normalized();
    let count = accessor.count();
    let size = component_size(t);
    let width = size * dims;
    let convert = |element: &[u8], out: &mut Vec<f32>| {
        for c in 0..dims {
            out.push(component_to_f32(&element[c * size..], t, normalized));
        }
    };
    let mut values = Vec::with_capacity(count.min(1 << 26) * dims);
    match accessor.view() {
        Some(view) => {
            let bytes = view_bytes(&view, buffers)?;
            let stride = view.stride().unwrap_or(width);
            if stride < width {
                return Err(format!(
                    "{what} accessor {}: byteStride {stride} is smaller than its {width}-byte elements",
                    accessor.index()
                ));
            }
            let elements =
                strided(bytes, accessor.offset(), stride, width, count).ok_or_else(|| {
                    format!(
                        "{what} accessor {} ({count} x {} {}) lies outside its bufferView",
                        accessor.index(),
                        dims,
                        type_name(t)
                    )
                })?;
            for element in elements {
                convert(element, &mut values);
            }
        }
        // No bufferView: all zeros (then sparse values, if any).
        None => values.resize(count * dims, 0.0),
    }
    if let Some(sparse) = accessor.sparse() {
        let n = sparse.count();
        let index_view = sparse.indices().view();
        let index_type = sparse.indices().index_type();
        let index_size = match index_type {
            gltf::accessor::sparse::IndexType::U8 => 1,
            gltf::accessor::sparse::IndexType::U16 => 2,
            gltf::accessor::sparse::IndexType::U32 => 4,
        };
        let index_bytes = view_bytes(&index_view, buffers)?;
        let indices = strided(
            index_bytes,
            sparse.indices().offset(),
            index_size,
            index_size,
            n,
        )
        .ok_or_else(|| {
            format!(
                "{what} accessor {}: sparse indices lie outside their bufferView",
                accessor.index()
            )
        })?;
        let value_view = sparse.values().view();
        let value_bytes = view_bytes(&value_view, buffers)?;
        let sparse_values = strided(value_bytes, sparse.values().offset(), width, width, n)
            .ok_or_else(|| {
                format!(
                    "{what} accessor {}: sparse values lie outside their bufferView",
                    accessor.index()
                )
            })?;
        for (index, element) in indices.zip(sparse_values) {
            let i = match index_size {
                1 => index[0] as usize,
                2 => u16::from_le_bytes([index[0], index[1]]) as usize,
                _ => u32::from_le_bytes([index[0], index[1], index[2], index[3]]) as usize,
            };
            if i >= count {
                return Err(format!(
                    "{what} accessor {}: sparse index {i} is out of range ({count} elements)",
                    accessor.index()
                ));
            }
            let mut decoded = Vec::with_capacity(dims);
            convert(element, &mut decoded);
            values[i * dims..(i + 1) * dims].copy_from_slice(&decoded);
        }
    }
    Ok(Floats { values, dims })
}

/// Reads an accessor of vectors with exactly `N` components (e.g. POSITION: 3).
pub(super) fn read_vectors<const N: usize>(
    accessor: &gltf::Accessor,
    buffers: &[Vec<u8>],
    what: &str,
) -> Result<Vec<[f32; N]>, String> {
    let floats = read_floats(accessor, buffers, what)?;
    if floats.dims != N {
        return Err(format!(
            "{what} accessor {} has {} components per element, {N} expected",
            accessor.index(),
            floats.dims
        ));
    }
    Ok(floats.to_arrays())
}

/// Checks an attribute's component type against what glTF and KHR_mesh_quantization allow for it.
pub(super) fn check_attribute_type(
    accessor: &gltf::Accessor,
    allowed: &[(DataType, Option<bool>)],
    what: &str,
) -> Result<(), String> {
    let t = accessor.data_type();
    let n = accessor.normalized();
    if allowed
        .iter()
        .any(|&(at, norm)| at == t && norm.is_none_or(|must| must == n))
    {
        Ok(())
    } else {
        Err(format!(
            "{what} accessor {} has component type {}{}, which glTF (with KHR_mesh_quantization) does not allow there",
            accessor.index(),
            if n { "normalized " } else { "" },
            type_name(t)
        ))
    }
}

/// Reads an index accessor (UNSIGNED_BYTE, UNSIGNED_SHORT or UNSIGNED_INT scalars).
pub(super) fn read_indices(
    accessor: &gltf::Accessor,
    buffers: &[Vec<u8>],
) -> Result<Vec<u32>, String> {
    let t = accessor.data_type();
    if !matches!(t, DataType::U8 | DataType::U16 | DataType::U32)
        || accessor.dimensions() != Dimensions::Scalar
        || accessor.sparse().is_some()
    {
        return Err(format!(
            "index accessor {} must be unsigned byte, short or int scalars without sparse storage",
            accessor.index()
        ));
    }
    let size = component_size(t);
    let view = accessor
        .view()
        .ok_or_else(|| format!("index accessor {} has no bufferView", accessor.index()))?;
    let bytes = view_bytes(&view, buffers)?;
    let stride = view.stride().unwrap_or(size).max(size);
    let elements = strided(bytes, accessor.offset(), stride, size, accessor.count())
        .ok_or("its index accessor lies outside its buffer")?;
    Ok(elements
        .map(|b| match size {
            1 => b[0] as u32,
            2 => u16::from_le_bytes([b[0], b[1]]) as u32,
            _ => u32::from_le_bytes([b[0], b[1], b[2], b[3]]),
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normalized_integers_follow_the_spec() {
        assert_eq!(component_to_f32(&[127], DataType::I8, true), 1.0);
        assert_eq!(component_to_f32(&[0x80], DataType::I8, true), -1.0);
        assert_eq!(component_to_f32(&[0x81], DataType::I8, true), -1.0);
        assert_eq!(component_to_f32(&[255], DataType::U8, true), 1.0);
        assert_eq!(
            component_to_f32(&(-32768i16).to_le_bytes(), DataType::I16, true),
            -1.0
        );
        assert_eq!(
            component_to_f32(&32767i16.to_le_bytes(), DataType::I16, true),
            1.0
        );
        assert_eq!(
            component_to_f32(&65535u16.to_le_bytes(), DataType::U16, true),
            1.0
        );
        assert_eq!(
            component_to_f32(&(-300i16).to_le_bytes(), DataType::I16, false),
            -300.0
        );
        assert_eq!(component_to_f32(&[200], DataType::U8, false), 200.0);
    }

    #[test]
    fn strided_reads_stop_at_the_end() {
        let bytes = [0u8; 16];
        assert!(strided(&bytes, 0, 8, 6, 2).is_some());
        assert!(strided(&bytes, 4, 8, 6, 2).is_none());
        assert!(strided(&bytes, 0, usize::MAX, 6, 3).is_none());
        assert_eq!(strided(&bytes, 0, 8, 6, 0).map(Iterator::count), Some(0));
    }
}
