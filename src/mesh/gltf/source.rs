//! The document and its binary data: parsing (GLB or JSON), validation, buffers and
//! accessors, every size checked before anything is allocated or sliced.

use std::borrow::Cow;
use std::cell::Cell;

use ::gltf::json;
use base64::Engine;
use json::accessor::{ComponentType, GenericComponentType, IndexComponentType, Type};
use json::validation::{Checked, Validate};

use crate::mesh::ImportError;

/// A [`ImportError::Parse`] of the glTF format.
pub(super) fn parse_error(detail: impl Into<String>) -> ImportError {
    ImportError::Parse {
        format: "gltf",
        detail: detail.into(),
    }
}

/// The most validation problems one error lists.
const LISTED: usize = 5;

/// The most bytes of POSITION data a reading decodes, as a multiple of the file's
/// length: each accessor is read once, and accessors of a sound file seldom overlap, so
/// only a file of many accessors over the same bytes (made to cost time and memory)
/// comes near.
const POSITION_BUDGET: u64 = 2;

/// Parses a glTF JSON or GLB file (told apart by the `glTF` magic) and validates it.
///
/// Returns the document and the GLB's BIN chunk, if any. Refused with
/// [`ImportError::Parse`] for a broken container, JSON the glTF schema does not
/// accept, or an index that names nothing. Never panics: the GLB header's length is
/// checked before the `gltf` crate reads it, and every primitive's `POSITION` index
/// before its validation looks that accessor up. A UTF-8 byte-order mark at the start
/// is skipped, and the magic looked for after it (the `gltf` crate is given the bytes
/// after the mark, and reads them as GLB when they start with `glTF`).
pub(super) fn parse(bytes: &[u8]) -> Result<(json::Root, Option<Vec<u8>>), ImportError> {
    let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    if bytes.starts_with(b"glTF") {
        check_glb_header(bytes)?;
    }
    let gltf = ::gltf::Gltf::from_slice_without_validation(bytes)
        .map_err(|e| parse_error(e.to_string()))?;
    let blob = gltf.blob;
    let root = gltf.document.into_json();
    check_position_indices(&root)?;
    validate(&root)?;
    Ok((root, blob))
}

/// The GLB header's version and length. The `gltf` crate subtracts 12 from the
/// declared length without a check, so a shorter one must not reach it.
fn check_glb_header(bytes: &[u8]) -> Result<(), ImportError> {
    let word = |at: usize| {
        bytes
            .get(at..at + 4)
            .map(|w| u32::from_le_bytes([w[0], w[1], w[2], w[3]]))
    };
    let (Some(version), Some(length)) = (word(4), word(8)) else {
        return Err(parse_error(format!(
            "a GLB file has a 12-byte header; this one has {} bytes",
            bytes.len()
        )));
    };
    if version != 2 {
        return Err(parse_error(format!(
            "GLB version {version}; only version 2 is read"
        )));
    }
    if length < 12 || length as usize > bytes.len() {
        return Err(parse_error(format!(
            "the GLB header gives a length of {length} bytes, but the file has {} bytes",
            bytes.len()
        )));
    }
    Ok(())
}

/// Every primitive's `POSITION` accessor exists (the `gltf` crate's validation indexes
/// it without looking).
fn check_position_indices(root: &json::Root) -> Result<(), ImportError> {
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let position = primitive
                .attributes
                .get(&Checked::Valid(json::mesh::Semantic::Positions));
            if let Some(a) = position
                && a.value() >= root.accessors.len()
            {
                return Err(parse_error(format!(
                    "mesh {m} primitive {p}: POSITION names accessor {}, but the file has {} \
                     accessors",
                    a.value(),
                    root.accessors.len()
                )));
            }
        }
    }
    Ok(())
}

/// The `gltf` crate's validation (indices in range, required fields, enumerations).
fn validate(root: &json::Root) -> Result<(), ImportError> {
    let mut errors = Vec::new();
    root.validate(root, json::Path::new, &mut |path, error| {
        errors.push(format!("{}: {error}", path()))
    });
    if errors.is_empty() {
        return Ok(());
    }
    let more = errors.len().saturating_sub(LISTED);
    errors.truncate(LISTED);
    let mut detail = format!("invalid glTF: {}", errors.join("; "));
    if more > 0 {
        detail.push_str(&format!(" (and {more} more)"));
    }
    Err(parse_error(detail))
}

/// The bytes of the buffers a reading needs, and the accessors read from them.
pub(super) struct Data<'a> {
    root: &'a json::Root,
    /// Each buffer's bytes (exactly its `byteLength`), `None` for one not resolved.
    buffers: Vec<Option<Cow<'a, [u8]>>>,
    /// The file's length: no accessor may describe more bytes than this.
    file_len: usize,
    /// The bytes of POSITION accessors decoded so far.
    decoded: Cell<u64>,
}

impl<'a> Data<'a> {
    /// Resolves the buffers `wanted` (indices into `root.buffers`): buffer 0 without a
    /// URI is the GLB's BIN chunk `blob`, a `data:` URI is decoded (base64).
    ///
    /// Refused with [`ImportError::Unsupported`] for a buffer in an external file (named
    /// by its URI) or a data URI that is not base64, [`ImportError::Parse`] for a
    /// missing BIN chunk, bad base64, or a buffer shorter than its `byteLength`.
    pub(super) fn resolve(
        root: &'a json::Root,
        blob: Option<&'a [u8]>,
        wanted: impl IntoIterator<Item = usize>,
        file_len: usize,
    ) -> Result<Data<'a>, ImportError> {
        let mut buffers: Vec<Option<Cow<'a, [u8]>>> = vec![None; root.buffers.len()];
        for b in wanted {
            let Some(buffer) = root.buffers.get(b) else {
                return Err(parse_error(format!("there is no buffer {b}")));
            };
            if buffers[b].is_some() {
                continue;
            }
            let bytes: Cow<'a, [u8]> = match buffer.uri.as_deref() {
                None => match blob {
                    Some(blob) if b == 0 => Cow::Borrowed(blob),
                    _ => {
                        return Err(parse_error(format!(
                            "buffer {b} has no URI, and there is no GLB BIN chunk for it"
                        )));
                    }
                },
                Some(uri) => Cow::Owned(data_uri(b, uri)?),
            };
            let declared = usize::try_from(buffer.byte_length.0).unwrap_or(usize::MAX);
            if declared > bytes.len() {
                return Err(parse_error(format!(
                    "buffer {b} declares {} bytes but holds {}",
                    buffer.byte_length.0,
                    bytes.len()
                )));
            }
            buffers[b] = Some(match bytes {
                Cow::Borrowed(s) => Cow::Borrowed(&s[..declared]),
                Cow::Owned(mut v) => {
                    v.truncate(declared);
                    Cow::Owned(v)
                }
            });
        }
        Ok(Data {
            root,
            buffers,
            file_len,
            decoded: Cell::new(0),
        })
    }

    /// The buffers accessor `a` reads from (its view's and its sparse views'); empty for
    /// an accessor or view that does not exist (reading it is refused later).
    pub(super) fn accessor_buffers(root: &json::Root, a: usize) -> Vec<usize> {
        let Some(accessor) = root.accessors.get(a) else {
            return Vec::new();
        };
        let mut views = Vec::new();
        views.extend(accessor.buffer_view);
        if let Some(sparse) = &accessor.sparse {
            views.push(sparse.indices.buffer_view);
            views.push(sparse.values.buffer_view);
        }
        views
            .into_iter()
            .filter_map(|v| root.buffer_views.get(v.value()))
            .map(|v| v.buffer.value())
            .collect()
    }

    /// Accessor `a` as f32 triples. Refused unless it is a FLOAT VEC3 accessor whose
    /// elements all lie within their buffer view, and while the POSITION data decoded
    /// stays within [`POSITION_BUDGET`] times the file's length.
    pub(super) fn vec3_f32(&self, a: usize) -> Result<Vec<[f32; 3]>, ImportError> {
        let accessor = self.accessor(a)?;
        let component = component(&accessor.component_type);
        let kind = match accessor.type_ {
            Checked::Valid(t) => Some(t),
            Checked::Invalid => None,
        };
        if component != Some(ComponentType::F32) || kind != Some(Type::Vec3) {
            return Err(parse_error(format!(
                "accessor {a} holds positions, which must be FLOAT VEC3 (it is {} {})",
                component.map_or("invalid".into(), |c| format!("{c:?}")),
                kind.map_or("invalid".into(), |t| format!("{t:?}")),
            )));
        }
        let total = self
            .decoded
            .get()
            .saturating_add(accessor.count.0.saturating_mul(12));
        let budget = POSITION_BUDGET.saturating_mul(self.file_len as u64);
        if total > budget {
            return Err(parse_error(format!(
                "the POSITION accessors read describe {total} bytes, more than {POSITION_BUDGET} \
                 times the file's {} bytes",
                self.file_len
            )));
        }
        self.decoded.set(total);
        self.elements(a, 12, |b| {
            [
                f32::from_le_bytes([b[0], b[1], b[2], b[3]]),
                f32::from_le_bytes([b[4], b[5], b[6], b[7]]),
                f32::from_le_bytes([b[8], b[9], b[10], b[11]]),
            ]
        })
    }

    /// Accessor `a` as vertex indices. Refused unless it is a SCALAR accessor of
    /// UNSIGNED_BYTE, UNSIGNED_SHORT or UNSIGNED_INT whose elements all lie within their
    /// buffer view.
    pub(super) fn indices(&self, a: usize) -> Result<Vec<u32>, ImportError> {
        let accessor = self.accessor(a)?;
        let component = component(&accessor.component_type);
        let scalar = matches!(accessor.type_, Checked::Valid(Type::Scalar));
        match component {
            Some(c @ (ComponentType::U8 | ComponentType::U16 | ComponentType::U32)) if scalar => {
                self.elements(a, c.size(), move |b| read_uint(b, c))
            }
            _ => Err(parse_error(format!(
                "accessor {a} holds indices, which must be SCALAR of UNSIGNED_BYTE, \
                 UNSIGNED_SHORT or UNSIGNED_INT"
            ))),
        }
    }

    fn accessor(&self, a: usize) -> Result<&'a json::Accessor, ImportError> {
        self.root
            .accessors
            .get(a)
            .ok_or_else(|| parse_error(format!("there is no accessor {a}")))
    }

    /// The bytes of buffer view `v` and its stride, if it gives one.
    fn view(
        &self,
        v: json::Index<json::buffer::View>,
    ) -> Result<(&[u8], Option<usize>), ImportError> {
        let index = v.value();
        let Some(view) = self.root.buffer_views.get(index) else {
            return Err(parse_error(format!("there is no buffer view {index}")));
        };
        let b = view.buffer.value();
        let Some(Some(data)) = self.buffers.get(b) else {
            return Err(parse_error(format!(
                "buffer view {index} names buffer {b}, which was not read"
            )));
        };
        let start = view.byte_offset.map_or(0, |o| o.0);
        let end = start.checked_add(view.byte_length.0);
        match end {
            Some(end) if end <= data.len() as u64 => {
                // Both fit in usize: they are at most the buffer's length.
                let bytes = &data[start as usize..end as usize];
                Ok((bytes, view.byte_stride.map(|s| s.0)))
            }
            _ => Err(parse_error(format!(
                "buffer view {index} runs from byte {start} for {} bytes, past the end of \
                 buffer {b} ({} bytes)",
                view.byte_length.0,
                data.len()
            ))),
        }
    }

    /// Accessor `a`'s `count` elements of `size` bytes each, decoded by `decode` (given
    /// exactly `size` bytes), with its sparse substitutions applied.
    ///
    /// Refused, before anything is allocated, when the elements would describe more
    /// bytes than the file holds or run past their buffer view, the stride is shorter
    /// than an element, or a sparse index is out of range.
    fn elements<T: Copy + Default>(
        &self,
        a: usize,
        size: usize,
        decode: impl Fn(&[u8]) -> T,
    ) -> Result<Vec<T>, ImportError> {
        let accessor = self.accessor(a)?;
        let count = accessor.count.0;
        let bytes = count.checked_mul(size as u64);
        if bytes.is_none_or(|b| b > self.file_len as u64) {
            return Err(parse_error(format!(
                "accessor {a} counts {count} elements of {size} bytes, more than the file's \
                 {} bytes",
                self.file_len
            )));
        }
        // Fits in usize: count · size is at most the file's length.
        let count = count as usize;
        let mut out = match accessor.buffer_view {
            Some(v) => {
                let (view, stride) = self.view(v)?;
                let stride = stride.unwrap_or(size);
                if stride < size {
                    return Err(parse_error(format!(
                        "accessor {a}: its buffer view's stride of {stride} bytes is shorter \
                         than its {size}-byte elements"
                    )));
                }
                let offset = accessor.byte_offset.map_or(0, |o| o.0);
                let last = (count as u64)
                    .checked_sub(1)
                    .map(|n| n.checked_mul(stride as u64));
                let end = match last {
                    None => Some(offset),
                    Some(Some(l)) => offset
                        .checked_add(l)
                        .and_then(|e| e.checked_add(size as u64)),
                    Some(None) => None,
                };
                if end.is_none_or(|e| e > view.len() as u64) {
                    return Err(parse_error(format!(
                        "accessor {a}: {count} elements of {size} bytes every {stride} from \
                         byte {offset} run past the end of its buffer view ({} bytes)",
                        view.len()
                    )));
                }
                // In range: checked just above.
                let view = &view[offset as usize..];
                (0..count)
                    .map(|i| decode(&view[i * stride..i * stride + size]))
                    .collect()
            }
            None if accessor.sparse.is_some() => vec![T::default(); count],
            None => {
                return Err(parse_error(format!(
                    "accessor {a} has neither a buffer view nor sparse values"
                )));
            }
        };
        if let Some(sparse) = &accessor.sparse {
            self.apply_sparse(a, sparse, size, &decode, &mut out)?;
        }
        Ok(out)
    }

    /// Replaces the elements a sparse accessor lists. Precondition: `out` holds the
    /// accessor's `count` elements.
    fn apply_sparse<T>(
        &self,
        a: usize,
        sparse: &json::accessor::sparse::Sparse,
        size: usize,
        decode: &impl Fn(&[u8]) -> T,
        out: &mut [T],
    ) -> Result<(), ImportError> {
        let n = sparse.count.0;
        if n > out.len() as u64 {
            return Err(parse_error(format!(
                "accessor {a}: {n} sparse values for {} elements",
                out.len()
            )));
        }
        // At most `out.len()`.
        let n = n as usize;
        let kind = match sparse.indices.component_type {
            Checked::Valid(IndexComponentType(
                c @ (ComponentType::U8 | ComponentType::U16 | ComponentType::U32),
            )) => c,
            _ => {
                return Err(parse_error(format!(
                    "accessor {a}: sparse indices must be UNSIGNED_BYTE, UNSIGNED_SHORT or \
                     UNSIGNED_INT"
                )));
            }
        };
        let indices = self.packed(
            a,
            sparse.indices.buffer_view,
            sparse.indices.byte_offset.0,
            n,
            kind.size(),
        )?;
        let values = self.packed(
            a,
            sparse.values.buffer_view,
            sparse.values.byte_offset.0,
            n,
            size,
        )?;
        let len = out.len();
        for (i, v) in indices
            .chunks_exact(kind.size())
            .zip(values.chunks_exact(size))
        {
            let i = read_uint(i, kind) as usize;
            let Some(slot) = out.get_mut(i) else {
                return Err(parse_error(format!(
                    "accessor {a}: sparse index {i} is past its {len} elements"
                )));
            };
            *slot = decode(v);
        }
        Ok(())
    }

    /// `n` tightly packed elements of `size` bytes from byte `offset` of view `v`.
    fn packed(
        &self,
        a: usize,
        v: json::Index<json::buffer::View>,
        offset: u64,
        n: usize,
        size: usize,
    ) -> Result<&[u8], ImportError> {
        let (view, _) = self.view(v)?;
        let end = (n as u64)
            .checked_mul(size as u64)
            .and_then(|b| b.checked_add(offset));
        match end {
            // In range: at most the view's length.
            Some(end) if end <= view.len() as u64 => Ok(&view[offset as usize..end as usize]),
            _ => Err(parse_error(format!(
                "accessor {a}: {n} sparse elements of {size} bytes from byte {offset} run past \
                 the end of buffer view {} ({} bytes)",
                v.value(),
                view.len()
            ))),
        }
    }
}

/// An accessor's component type, `None` when it is not one glTF defines.
fn component(c: &Checked<GenericComponentType>) -> Option<ComponentType> {
    match c {
        Checked::Valid(GenericComponentType(c)) => Some(*c),
        Checked::Invalid => None,
    }
}

/// An unsigned integer of `kind` (U8, U16 or U32), little-endian, from the first bytes of
/// `b`. Precondition: `b` holds at least `kind.size()` bytes.
fn read_uint(b: &[u8], kind: ComponentType) -> u32 {
    match kind {
        ComponentType::U8 => u32::from(b[0]),
        ComponentType::U16 => u32::from(u16::from_le_bytes([b[0], b[1]])),
        _ => u32::from_le_bytes([b[0], b[1], b[2], b[3]]),
    }
}

/// The bytes of buffer `b`'s `data:` URI. Refused with [`ImportError::Unsupported`] for
/// any other URI (winged has no files to look in) or a data URI that is not base64, and
/// [`ImportError::Parse`] for bad base64.
fn data_uri(b: usize, uri: &str) -> Result<Vec<u8>, ImportError> {
    let external = || ImportError::Unsupported {
        detail: format!(
            "glTF buffer {b} is in the external file {uri:?}; winged reads buffers only from \
             a GLB's BIN chunk or data: URIs"
        ),
    };
    let Some(rest) = uri
        .get(..5)
        .filter(|s| s.eq_ignore_ascii_case("data:"))
        .and_then(|_| uri.get(5..))
    else {
        return Err(external());
    };
    let Some((meta, payload)) = rest.split_once(',') else {
        return Err(parse_error(format!(
            "buffer {b}: a data URI without a comma"
        )));
    };
    let base64 = meta
        .len()
        .checked_sub(7)
        .and_then(|k| meta.get(k..))
        .is_some_and(|s| s.eq_ignore_ascii_case(";base64"));
    if !base64 {
        return Err(ImportError::Unsupported {
            detail: format!("glTF buffer {b} is a data URI that is not base64 ({meta:?})"),
        });
    }
    base64::engine::general_purpose::STANDARD_PAD_INDIFFERENT
        .decode(payload.trim())
        .map_err(|e| parse_error(format!("buffer {b}: bad base64 in its data URI: {e}")))
}
