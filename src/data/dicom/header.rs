//! What a DICOM file's header says: each length checked before dicom-rs
//! takes it, and the slices (frames) it describes.

use std::io::Read;
use std::path::Path;

use dicom_core::{Tag, VR};
use dicom_dictionary_std::tags;
use dicom_encoding::transfer_syntax::{Codec, TransferSyntaxIndex};
use dicom_encoding::TransferSyntax;
use dicom_object::{mem::InMemElement, InMemDicomObject};
use dicom_transfer_syntax_registry::TransferSyntaxRegistry;
use glam::{DVec2, DVec3};

use super::super::stored::{Stored, ZLIB_MAX_RATIO};
use super::super::{bad, DataError};
use super::series::Slice;
use super::{one_line, tag_name, Object};

/// Where a file's header is at fault: the tag (none for the file as a
/// whole), and why.
type Fault = (Option<Tag>, String);

/// Checks that every length the file `bytes` declares fits in the bytes
/// after it, before dicom-rs takes it (its parser reserves and zeroes
/// whatever length a header claims); returns its transfer syntax's UID.
/// dicom-rs's own decoders read the headers; a deflated data set is
/// inflated to at most the ratio deflate reaches.
pub(super) fn lengths_fit(bytes: &[u8]) -> Result<String, Fault> {
    let file = None;
    let Some(body) = bytes.get(132..).filter(|_| &bytes[128..132] == b"DICM") else {
        return Err((
            file,
            "not a DICOM file (no DICM after a 128-byte preamble)".into(),
        ));
    };
    let registry = TransferSyntaxRegistry;
    let explicit = registry
        .get("1.2.840.10008.1.2.1")
        .ok_or((file, "no explicit VR".into()))?;
    let (walked, uid) = walk(body, explicit, true)?;
    let why = "its file meta group names no transfer syntax (0002,0010)";
    let uid = uid.ok_or((file, why.into()))?;
    let data = &body[walked..];
    match registry.get(&uid) {
        Some(ts) if matches!(ts.codec(), Codec::Dataset(_)) => {
            let limit = (data.len() as u64).saturating_mul(ZLIB_MAX_RATIO as u64);
            let mut inflated = Vec::new();
            let mut inflater = flate2::read::DeflateDecoder::new(data).take(limit);
            let why = |e| (file, format!("its deflated data set: {e}"));
            inflater.read_to_end(&mut inflated).map_err(why)?;
            walk(&inflated, explicit, false)?;
        }
        Some(ts) => _ = walk(data, ts, false)?,
        None => {}
    }
    Ok(uid)
}

/// Walks the element headers of `data` in `syntax`, stepping into
/// sequences and their items, each defined length checked against the
/// bytes left; with `meta`, only the file meta group. Returns the bytes
/// walked and the transfer syntax UID where met.
fn walk(
    data: &[u8],
    syntax: &TransferSyntax,
    meta: bool,
) -> Result<(usize, Option<String>), Fault> {
    let decoder = syntax.decoder_for::<&[u8]>();
    let decoder = decoder.ok_or((None, format!("{} has no decoder", syntax.name())))?;
    let (mut rest, mut fragments, mut uid) = (data, false, None);
    while !rest.is_empty() && (!meta || rest.starts_with(&[2, 0])) {
        let at = data.len() - rest.len();
        let (header, _) = decoder.decode_header(&mut rest).map_err(|e| {
            (
                None,
                format!("the element header at byte {at}: {}", one_line(&e)),
            )
        })?;
        let tag = header.tag;
        // Encapsulated pixel data: items of fragments up to a sequence end.
        fragments &= tag != Tag(0xFFFE, 0xE0DD);
        let Some(len) = header.len.get() else {
            fragments |= tag == tags::PIXEL_DATA;
            continue;
        };
        if header.vr == VR::SQ || (tag == Tag(0xFFFE, 0xE000) && !fragments) {
            continue;
        }
        let Some(value) = rest.get(..len as usize) else {
            return Err((
                Some(tag),
                format!("{len} bytes declared where {} are left", rest.len()),
            ));
        };
        if tag == tags::TRANSFER_SYNTAX_UID {
            let text = String::from_utf8_lossy(value);
            uid = Some(text.trim_end_matches(['\0', ' ']).to_string());
        }
        rest = &rest[len as usize..];
    }
    Ok((data.len() - rest.len(), uid))
}

/// `tag` for `frame`: from that frame's functional groups, else the
/// shared ones, else the data set's top level.
fn find(object: &InMemDicomObject, frame: Option<usize>, tag: Tag) -> Option<&InMemElement> {
    let within = |sequence, k: usize| {
        let group = object.get(sequence)?.items()?.get(k)?;
        group.iter().find_map(|e| e.items()?.first()?.get(tag))
    };
    frame
        .and_then(|k| within(tags::PER_FRAME_FUNCTIONAL_GROUPS_SEQUENCE, k))
        .or_else(|| within(tags::SHARED_FUNCTIONAL_GROUPS_SEQUENCE, 0))
        .or_else(|| object.get(tag))
}

/// The slices of `object` (one a frame), every field checked.
pub(super) fn slices_of(object: &Object, file: &Path) -> Result<Vec<Slice>, DataError> {
    let name = file.display().to_string();
    let check = |ok: bool, tag: Tag, why: String| match ok {
        true => Ok(()),
        false => Err(bad(&name, &tag_name(tag), why)),
    };
    let int = |tag: Tag, default: i64| -> Result<i64, DataError> {
        match object.get(tag).map(|e| e.to_int::<i64>()) {
            None => Ok(default),
            Some(Ok(n)) => Ok(n),
            Some(Err(_)) => check(false, tag, "not an integer".into()).map(|_| 0),
        }
    };
    let size = |tag| -> Result<u32, DataError> {
        check(object.get(tag).is_some(), tag, "missing".into())?;
        let n = int(tag, 0)?;
        check(
            n > 0 && n <= i64::from(u32::MAX),
            tag,
            format!("{n} is not a size"),
        )?;
        Ok(n as u32)
    };
    let frames = int(tags::NUMBER_OF_FRAMES, 1)?;
    let per_frame = object.get(tags::PER_FRAME_FUNCTIONAL_GROUPS_SEQUENCE);
    let placed = per_frame.and_then(|e| e.items()).map_or(0, |i| i.len()) as i64;
    let why = format!(
        "{frames} frames, {placed} of them placed by a PerFrameFunctionalGroupsSequence: \
         caveray reads frames the headers place"
    );
    check(
        frames == 1 || (frames > 1 && placed == frames),
        tags::NUMBER_OF_FRAMES,
        why,
    )?;
    let samples = int(tags::SAMPLES_PER_PIXEL, 1)?;
    let why = format!("{samples} samples a pixel: caveray reads scalar (grey) images");
    check(samples == 1, tags::SAMPLES_PER_PIXEL, why)?;
    let (rows, columns) = (size(tags::ROWS)?, size(tags::COLUMNS)?);
    let bits = size(tags::BITS_ALLOCATED)?;
    let sign = int(tags::PIXEL_REPRESENTATION, 0)?;
    let why = format!("{sign} is neither 0 (unsigned) nor 1 (signed)");
    check(sign == 0 || sign == 1, tags::PIXEL_REPRESENTATION, why)?;
    let types = [
        Stored::U8,
        Stored::I8,
        Stored::U16,
        Stored::I16,
        Stored::U32,
        Stored::I32,
    ];
    let stored = types.into_iter().find(|t| {
        t.bytes() * 8 == u64::from(bits)
            && (sign == 1) == matches!(t, Stored::I8 | Stored::I16 | Stored::I32)
    });
    let why = format!("{bits}: caveray reads 8, 16 and 32-bit pixels");
    check(stored.is_some(), tags::BITS_ALLOCATED, why)?;
    let bits_stored = int(tags::BITS_STORED, i64::from(bits))?;
    let why = format!("{bits_stored} of {bits} allocated bits");
    check(
        (1..=i64::from(bits)).contains(&bits_stored),
        tags::BITS_STORED,
        why,
    )?;
    let text = |tag| {
        let text = object.get(tag).and_then(|e| e.to_str().ok());
        text.map_or(String::new(), |t| t.trim_end_matches(['\0', ' ']).into())
    };
    let frame = |k: u32| -> Result<Slice, DataError> {
        let at = (frames > 1).then_some(k as usize);
        // A field's numbers, checked to be `n` where given.
        let numbers = |tag: Tag, n: Option<usize>| -> Result<Option<Vec<f64>>, DataError> {
            let Some(e) = find(object, at, tag) else {
                return check(n.is_none(), tag, "missing".into()).map(|_| None);
            };
            let v = e
                .to_multi_float64()
                .ok()
                .filter(|v| v.iter().all(|x| x.is_finite()));
            let text = e.to_str().unwrap_or_default();
            let v =
                v.ok_or_else(|| bad(&name, &tag_name(tag), format!("'{text}' is not numbers")))?;
            let why = format!("{} values where {} are needed", v.len(), n.unwrap_or(0));
            check(n.is_none_or(|n| v.len() == n), tag, why)?;
            Ok(Some(v))
        };
        let floats = |tag, n| Ok::<_, DataError>(numbers(tag, Some(n))?.unwrap_or_default());
        let first = |tag| Ok::<_, DataError>(numbers(tag, None)?.and_then(|v| v.first().copied()));
        let turn = floats(tags::IMAGE_ORIENTATION_PATIENT, 6)?;
        let (row_axis, column_axis) = (DVec3::from_slice(&turn), DVec3::from_slice(&turn[3..]));
        let unit = |v: DVec3| (v.length() - 1.0).abs() < 1e-3;
        let why = "its row and column directions are not orthogonal unit vectors";
        let square = unit(row_axis) && unit(column_axis) && row_axis.dot(column_axis).abs() < 1e-3;
        check(square, tags::IMAGE_ORIENTATION_PATIENT, why.into())?;
        let position = DVec3::from_slice(&floats(tags::IMAGE_POSITION_PATIENT, 3)?);
        let pixel_spacing = DVec2::from_slice(&floats(tags::PIXEL_SPACING, 2)?);
        let why = format!("{pixel_spacing} is not positive");
        check(pixel_spacing.min_element() > 0.0, tags::PIXEL_SPACING, why)?;
        let slope = first(tags::RESCALE_SLOPE)?.unwrap_or(1.0);
        check(slope != 0.0, tags::RESCALE_SLOPE, "zero".into())?;
        let thickness = first(tags::SPACING_BETWEEN_SLICES)?.or(first(tags::SLICE_THICKNESS)?);
        Ok(Slice {
            file: file.to_path_buf(),
            frame: k,
            series: text(tags::SERIES_INSTANCE_UID),
            rows,
            columns,
            row_axis: row_axis.normalize(),
            column_axis: column_axis.normalize(),
            pixel_spacing,
            position,
            stored: stored.unwrap_or(Stored::U8),
            bits_stored: bits_stored as u16,
            slope,
            intercept: first(tags::RESCALE_INTERCEPT)?.unwrap_or(0.0),
            thickness: thickness.filter(|t| *t > 0.0),
            modality: text(tags::MODALITY),
            transfer_syntax: object.meta().transfer_syntax().to_string(),
        })
    };
    (0..frames as u32).map(frame).collect()
}
