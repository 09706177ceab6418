//! EXT_meshopt_compression and KHR_meshopt_compression: bufferViews whose bytes are meshoptimizer-encoded
//! (vertex attributes, triangle indices or index sequences, then an optional octahedral / quaternion /
//! exponential / colour filter). Each compressed view is decoded once, before anything reads the file, into
//! the place its uncompressed bytes would have in its (fallback) buffer; every accessor, image and animation
//! reader then sees plain data. Decoding uses meshoptimizer's own C++ decoders (the `meshopt` crate), which
//! are written to be safe on untrusted input; the preconditions they only assert are checked here first.

pub(super) const EXTENSIONS: [&str; 2] = ["EXT_meshopt_compression", "KHR_meshopt_compression"];

/// The compression parameters of one bufferView.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct CompressedView {
    pub buffer: usize,
    pub offset: usize,
    pub length: usize,
    pub stride: usize,
    pub count: usize,
    pub mode: Mode,
    pub filter: Filter,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Mode {
    Attributes,
    Triangles,
    Indices,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Filter {
    None,
    Octahedral,
    Quaternion,
    Exponential,
    Color,
}

/// The extension object of a compressed view, if the view has one (either extension name).
pub(super) fn extension_of<'v>(view: &'v gltf::buffer::View) -> Option<&'v serde_json::Value> {
    EXTENSIONS.iter().find_map(|e| view.extension_value(e))
}

/// True for a buffer that only exists to give compressed views a place (`"fallback": true`).
pub(super) fn is_fallback_buffer(buffer: &gltf::Buffer) -> bool {
    EXTENSIONS.iter().any(|e| {
        buffer
            .extension_value(e)
            .and_then(|v| v.get("fallback"))
            .and_then(serde_json::Value::as_bool)
            == Some(true)
    })
}

impl CompressedView {
    pub fn parse(extension: &serde_json::Value) -> Result<Self, String> {
        let field = |name: &str| -> Result<usize, String> {
            extension
                .get(name)
                .and_then(serde_json::Value::as_u64)
                .map(|v| v as usize)
                .ok_or_else(|| format!("`{name}` is missing or not an unsigned integer"))
        };
        let mode = match extension.get("mode").and_then(serde_json::Value::as_str) {
            Some("ATTRIBUTES") => Mode::Attributes,
            Some("TRIANGLES") => Mode::Triangles,
            Some("INDICES") => Mode::Indices,
            other => return Err(format!("unknown mode {other:?}")),
        };
        let filter = match extension.get("filter").and_then(serde_json::Value::as_str) {
            None | Some("NONE") => Filter::None,
            Some("OCTAHEDRAL") => Filter::Octahedral,
            Some("QUATERNION") => Filter::Quaternion,
            Some("EXPONENTIAL") => Filter::Exponential,
            Some("COLOR") => Filter::Color,
            Some(other) => return Err(format!("unknown filter `{other}`")),
        };
        Ok(Self {
            buffer: field("buffer")?,
            offset: extension
                .get("byteOffset")
                .map_or(Ok(0), |_| field("byteOffset"))?,
            length: field("byteLength")?,
            stride: field("byteStride")?,
            count: field("count")?,
            mode,
            filter,
        })
    }

    /// Decoded size in bytes.
    pub fn decoded_len(&self) -> Option<usize> {
        self.count.checked_mul(self.stride)
    }

    /// Decodes `source` (the compressed bytes) into `count * stride` bytes.
    pub fn decode(&self, source: &[u8]) -> Result<Vec<u8>, String> {
        let len = self
            .decoded_len()
            .filter(|&l| l <= 1 << 31)
            .ok_or("count x byteStride is too large")?;
        let mut out = vec![0u8; len];
        let code = match self.mode {
            Mode::Attributes => {
                if self.stride == 0 || self.stride > 256 || !self.stride.is_multiple_of(4) {
                    return Err(format!(
                        "ATTRIBUTES byteStride {} must be a multiple of 4 up to 256",
                        self.stride
                    ));
                }
                // SAFETY: `out` holds count x stride bytes and the stride meets the decoder's preconditions.
                unsafe {
                    meshopt::ffi::meshopt_decodeVertexBuffer(
                        out.as_mut_ptr().cast(),
                        self.count,
                        self.stride,
                        source.as_ptr(),
                        source.len(),
                    )
                }
            }
            Mode::Triangles | Mode::Indices => {
                if self.stride != 2 && self.stride != 4 {
                    return Err(format!(
                        "{:?} byteStride {} must be 2 or 4",
                        self.mode, self.stride
                    ));
                }
                if self.mode == Mode::Triangles && !self.count.is_multiple_of(3) {
                    return Err(format!(
                        "TRIANGLES count {} is not a multiple of 3",
                        self.count
                    ));
                }
                // SAFETY: as above; the index size is 2 or 4 and triangle counts are whole.
                unsafe {
                    if self.mode == Mode::Triangles {
                        meshopt::ffi::meshopt_decodeIndexBuffer(
                            out.as_mut_ptr().cast(),
                            self.count,
                            self.stride,
                            source.as_ptr(),
                            source.len(),
                        )
                    } else {
                        meshopt::ffi::meshopt_decodeIndexSequence(
                            out.as_mut_ptr().cast(),
                            self.count,
                            self.stride,
                            source.as_ptr(),
                            source.len(),
                        )
                    }
                }
            }
        };
        if code != 0 {
            return Err(format!(
                "the meshoptimizer decoder rejected the data (code {code}: {})",
                if code == -2 {
                    "truncated"
                } else {
                    "malformed or an unknown version"
                }
            ));
        }
        self.unfilter(&mut out)?;
        Ok(out)
    }

    fn unfilter(&self, data: &mut [u8]) -> Result<(), String> {
        if self.filter == Filter::None {
            return Ok(());
        }
        if self.mode != Mode::Attributes {
            return Err(format!("filter {:?} on {:?} data", self.filter, self.mode));
        }
        let stride_ok = match self.filter {
            Filter::Octahedral | Filter::Color => self.stride == 4 || self.stride == 8,
            Filter::Quaternion => self.stride == 8,
            Filter::Exponential => self.stride.is_multiple_of(4),
            Filter::None => true,
        };
        if !stride_ok {
            return Err(format!(
                "filter {:?} does not allow byteStride {}",
                self.filter, self.stride
            ));
        }
        let (ptr, count, stride) = (data.as_mut_ptr().cast(), self.count, self.stride);
        // SAFETY: `data` holds count x stride bytes and the stride is one the filter accepts.
        unsafe {
            match self.filter {
                Filter::Octahedral => meshopt::ffi::meshopt_decodeFilterOct(ptr, count, stride),
                Filter::Quaternion => meshopt::ffi::meshopt_decodeFilterQuat(ptr, count, stride),
                Filter::Exponential => meshopt::ffi::meshopt_decodeFilterExp(ptr, count, stride),
                Filter::Color => meshopt::ffi::meshopt_decodeFilterColor(ptr, count, stride),
                Filter::None => {}
            }
        }
        Ok(())
    }
}

/// Decodes every compressed bufferView of `document` into `buffers` (at the view's own place). Returns the
/// views that failed, each with its reason; their bytes stay as they were (zeros in a fallback buffer).
pub(super) fn decode_views(
    document: &gltf::Document,
    buffers: &mut [Vec<u8>],
) -> Vec<(usize, String)> {
    let mut failed = Vec::new();
    for view in document.views() {
        let Some(extension) = extension_of(&view) else {
            continue;
        };
        let result = CompressedView::parse(extension).and_then(|c| {
            let source = buffers
                .get(c.buffer)
                .and_then(|b| b.get(c.offset..c.offset.checked_add(c.length)?))
                .ok_or("its compressed bytes lie outside their buffer")?;
            let decoded = c.decode(source)?;
            if decoded.len() > view.length() {
                return Err(format!(
                    "it decodes to {} bytes but the bufferView is {} bytes long",
                    decoded.len(),
                    view.length()
                ));
            }
            let target = buffers
                .get_mut(view.buffer().index())
                .and_then(|b| b.get_mut(view.offset()..view.offset().checked_add(decoded.len())?))
                .ok_or("the bufferView lies outside its buffer")?;
            target.copy_from_slice(&decoded);
            Ok(())
        });
        if let Err(reason) = result {
            failed.push((view.index(), reason));
        }
    }
    failed
}
