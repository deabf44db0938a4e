//! One DICOM file (PS3.10: a preamble, `DICM`, the file meta group, then
//! the data set in its transfer syntax) read as far as a volume needs:
//! the top-level elements' values and the pixel data, native or
//! encapsulated. Every length the file declares is checked against the
//! bytes that follow before anything is taken, so a broken or hostile file
//! costs no more memory than its own size (dicom-rs 0.10 reserves and
//! zeroes whatever length a header claims, and its RLE and JPEG adapters
//! panic on some broken frames). Sequences are stepped over: no field a
//! volume needs lies inside one.

use std::io::Read;

use super::super::stored::ZLIB_MAX_RATIO;

/// The transfer syntaxes whose data sets are not explicit VR little-endian.
const IMPLICIT_LITTLE: &str = "1.2.840.10008.1.2";
const EXPLICIT_BIG: &str = "1.2.840.10008.1.2.2";
const DEFLATED: &str = "1.2.840.10008.1.2.1.99";
/// The compressed ones decoded: RLE Lossless (PS3.5 Annex G) and the JPEG
/// processes of grey images (baseline, extended, lossless, and lossless
/// with first-order prediction).
const RLE_LOSSLESS: &str = "1.2.840.10008.1.2.5";
const JPEG: [&str; 4] = [
    "1.2.840.10008.1.2.4.50",
    "1.2.840.10008.1.2.4.51",
    "1.2.840.10008.1.2.4.57",
    "1.2.840.10008.1.2.4.70",
];

const PIXEL_DATA: u32 = 0x7FE0_0010;
const ITEM: u32 = 0xFFFE_E000;
const ITEM_END: u32 = 0xFFFE_E00D;
const SEQUENCE_END: u32 = 0xFFFE_E0DD;

/// Top-level elements' values: (group << 16 | element, value), in file
/// order.
type Values = Vec<(u32, Vec<u8>)>;

/// The pixel data as stored.
enum Pixels {
    Absent,
    /// Samples in the data set's byte order.
    Native(Vec<u8>),
    /// Encapsulated: the fragments after the offset table, which together
    /// hold the one frame.
    Fragments(Vec<Vec<u8>>),
}

/// A file's top-level elements and pixel data.
pub(super) struct DataSet {
    /// The transfer syntax's UID.
    pub syntax: String,
    big_endian: bool,
    values: Values,
    pixels: Pixels,
}

impl DataSet {
    /// The data set of `bytes`, a whole file from its preamble; its pixel
    /// data kept only `with_pixels`.
    pub fn parse(bytes: &[u8], with_pixels: bool) -> Result<Self, String> {
        let rest = match bytes.get(128..132) {
            Some(b"DICM") => &bytes[132..],
            _ => return Err("not a DICOM file (no DICM after a 128-byte preamble)".into()),
        };
        // The file meta group: explicit VR little-endian.
        let mut at = 0;
        let mut syntax = String::new();
        while let Some(header) = Header::read(rest, at, Syntax::EXPLICIT_LITTLE)? {
            if header.tag >> 16 != 0x0002 {
                break;
            }
            let end = header.end(rest)?;
            if header.tag == 0x0002_0010 {
                syntax = text(&rest[header.value..end]);
            }
            at = end;
        }
        if syntax.is_empty() {
            return Err("its file meta group names no transfer syntax (0002,0010)".into());
        }
        let body = &rest[at.min(rest.len())..];
        let inflated;
        let (data, form) = match syntax.as_str() {
            IMPLICIT_LITTLE => (body, Syntax::IMPLICIT_LITTLE),
            EXPLICIT_BIG => (body, Syntax::EXPLICIT_BIG),
            DEFLATED => {
                let limit = (body.len() as u64).saturating_mul(ZLIB_MAX_RATIO as u64);
                let mut out = Vec::new();
                flate2::read::DeflateDecoder::new(body)
                    .take(limit)
                    .read_to_end(&mut out)
                    .map_err(|e| format!("its deflated data set: {e}"))?;
                inflated = out;
                (&inflated[..], Syntax::EXPLICIT_LITTLE)
            }
            _ => (body, Syntax::EXPLICIT_LITTLE),
        };
        let (values, pixels) = walk(data, form, with_pixels)?;
        Ok(Self {
            syntax,
            big_endian: form.big_endian,
            values,
            pixels,
        })
    }

    fn value(&self, tag: u32) -> Option<&[u8]> {
        self.values
            .iter()
            .find(|(t, _)| *t == tag)
            .map(|(_, v)| v.as_slice())
    }

    /// A text value (UI, CS, LO, ...), its padding trimmed.
    pub fn text(&self, tag: u32) -> Option<String> {
        self.value(tag).map(text)
    }

    /// A decimal or integer string's numbers (DS, IS), `\`-separated;
    /// None where one is not a finite number.
    pub fn numbers(&self, tag: u32) -> Option<Vec<f64>> {
        let text = self.text(tag)?;
        text.split('\\')
            .map(|s| s.trim().parse::<f64>().ok().filter(|v| v.is_finite()))
            .collect()
    }

    /// An unsigned short (US).
    pub fn us(&self, tag: u32) -> Option<u16> {
        let b: [u8; 2] = self.value(tag)?.get(..2)?.try_into().ok()?;
        Some(if self.big_endian {
            u16::from_be_bytes(b)
        } else {
            u16::from_le_bytes(b)
        })
    }

    /// The frame's samples, `pixels` of `width` bytes each, in the
    /// machine's byte order: native data as stored, RLE and JPEG decoded.
    pub fn frame(&self, columns: u32, rows: u32, width: usize) -> Result<Vec<u8>, String> {
        let pixels = columns as usize * rows as usize;
        let bytes = pixels * width;
        match &self.pixels {
            Pixels::Absent => Err("missing".into()),
            Pixels::Native(data) => {
                let mut out = data
                    .get(..bytes)
                    .ok_or_else(|| {
                        format!(
                            "{} bytes where {columns}x{rows} pixels of {width} bytes need {bytes}",
                            data.len()
                        )
                    })?
                    .to_vec();
                if self.big_endian != cfg!(target_endian = "big") {
                    out.chunks_exact_mut(width).for_each(|c| c.reverse());
                }
                Ok(out)
            }
            Pixels::Fragments(fragments) => {
                // One frame may be split over fragments: they are its
                // bytes in order.
                let frame: Vec<u8> = fragments.iter().flatten().copied().collect();
                if self.syntax == RLE_LOSSLESS {
                    rle_frame(&frame, pixels, width)
                } else if JPEG.contains(&self.syntax.as_str()) {
                    jpeg_frame(&frame, columns, rows, width)
                } else {
                    Err(format!(
                        "transfer syntax {} is not one caveray decodes (uncompressed, deflate, \
                         RLE, JPEG baseline, extended or lossless)",
                        self.syntax
                    ))
                }
            }
        }
    }
}

/// How a data set writes its element headers.
#[derive(Clone, Copy)]
struct Syntax {
    explicit: bool,
    big_endian: bool,
}

impl Syntax {
    const EXPLICIT_LITTLE: Self = Self {
        explicit: true,
        big_endian: false,
    };
    const EXPLICIT_BIG: Self = Self {
        explicit: true,
        big_endian: true,
    };
    const IMPLICIT_LITTLE: Self = Self {
        explicit: false,
        big_endian: false,
    };
}

/// An element's header: its tag, whether it is a sequence by its VR,
/// where its value starts and its declared length (`None`: undefined).
struct Header {
    tag: u32,
    sequence: bool,
    value: usize,
    length: Option<u32>,
}

impl Header {
    /// The header at `at` of `data`; None at the end of the data, an error
    /// where one is cut short.
    fn read(data: &[u8], at: usize, syntax: Syntax) -> Result<Option<Self>, String> {
        if at >= data.len() {
            return Ok(None);
        }
        let short = || format!("an element header at byte {at} is cut short");
        let u16_at = |i: usize| -> Result<u16, String> {
            let b: [u8; 2] = data
                .get(i..i + 2)
                .and_then(|b| b.try_into().ok())
                .ok_or_else(short)?;
            Ok(if syntax.big_endian {
                u16::from_be_bytes(b)
            } else {
                u16::from_le_bytes(b)
            })
        };
        let u32_at = |i: usize| -> Result<u32, String> {
            let b: [u8; 4] = data
                .get(i..i + 4)
                .and_then(|b| b.try_into().ok())
                .ok_or_else(short)?;
            Ok(if syntax.big_endian {
                u32::from_be_bytes(b)
            } else {
                u32::from_le_bytes(b)
            })
        };
        let tag = (u32::from(u16_at(at)?) << 16) | u32::from(u16_at(at + 2)?);
        let defined = |n: u32| (n != u32::MAX).then_some(n);
        // Items and delimiters carry no VR in any syntax.
        if tag >> 16 == 0xFFFE || !syntax.explicit {
            return Ok(Some(Self {
                tag,
                sequence: false,
                value: at + 8,
                length: defined(u32_at(at + 4)?),
            }));
        }
        let vr = data.get(at + 4..at + 6).ok_or_else(short)?;
        // VRs other than these have a 4-byte length after two reserved
        // bytes (PS3.5 7.1.2); an unknown one is read so too.
        let two_byte_length = matches!(
            vr,
            b"AE"
                | b"AS"
                | b"AT"
                | b"CS"
                | b"DA"
                | b"DS"
                | b"DT"
                | b"FL"
                | b"FD"
                | b"IS"
                | b"LO"
                | b"LT"
                | b"PN"
                | b"SH"
                | b"SL"
                | b"SS"
                | b"ST"
                | b"TM"
                | b"UI"
                | b"UL"
                | b"US"
        );
        let (value, length) = if two_byte_length {
            (at + 8, Some(u32::from(u16_at(at + 6)?)))
        } else {
            (at + 12, defined(u32_at(at + 8)?))
        };
        Ok(Some(Self {
            tag,
            sequence: vr == b"SQ",
            value,
            length,
        }))
    }

    /// Where a value of defined length ends, if it ends within `data`.
    fn end(&self, data: &[u8]) -> Result<usize, String> {
        let length = self.length.unwrap_or(0) as usize;
        let end = self.value.saturating_add(length);
        if end > data.len() {
            return Err(format!(
                "element ({:04X},{:04X}) says it holds {length} bytes; {} are left",
                self.tag >> 16,
                self.tag & 0xFFFF,
                data.len().saturating_sub(self.value)
            ));
        }
        Ok(end)
    }
}

/// The top-level elements of `data` and its pixel data. Sequences and
/// items of defined length are stepped over whole; those of undefined
/// length are walked to their delimiters, their elements passed over.
fn walk(data: &[u8], syntax: Syntax, with_pixels: bool) -> Result<(Values, Pixels), String> {
    let mut values = Vec::new();
    let mut pixels = Pixels::Absent;
    let mut depth = 0usize;
    let mut at = 0;
    while let Some(header) = Header::read(data, at, syntax)? {
        let end = header.end(data)?;
        match (header.tag, header.length) {
            (ITEM_END | SEQUENCE_END, _) => {
                depth = depth.saturating_sub(1);
                at = end;
            }
            (PIXEL_DATA, None) if depth == 0 => {
                let (fragments, after) = fragments(data, header.value, syntax)?;
                if with_pixels {
                    pixels = Pixels::Fragments(fragments);
                }
                at = after;
            }
            // A sequence or item of undefined length: its elements follow.
            (_, None) => {
                depth += 1;
                at = header.value;
            }
            (PIXEL_DATA, Some(_)) if depth == 0 => {
                if with_pixels {
                    pixels = Pixels::Native(data[header.value..end].to_vec());
                }
                at = end;
            }
            (tag, Some(_)) => {
                if depth == 0 && !header.sequence && tag != ITEM {
                    values.push((tag, data[header.value..end].to_vec()));
                }
                at = end;
            }
        }
    }
    Ok((values, pixels))
}

/// The fragments of encapsulated pixel data whose items start at `at`,
/// the offset table left out, and where the sequence ends.
fn fragments(data: &[u8], mut at: usize, syntax: Syntax) -> Result<(Vec<Vec<u8>>, usize), String> {
    let mut items = Vec::new();
    loop {
        let header = Header::read(data, at, syntax)?
            .ok_or("the encapsulated pixel data has no end (FFFE,E0DD)")?;
        let end = header.end(data)?;
        match header.tag {
            ITEM if header.length.is_some() => items.push(data[header.value..end].to_vec()),
            SEQUENCE_END => return Ok((items.into_iter().skip(1).collect(), end)),
            tag => {
                return Err(format!(
                    "({:04X},{:04X}) where encapsulated pixel data holds items of defined length",
                    tag >> 16,
                    tag & 0xFFFF
                ))
            }
        }
        at = end;
    }
}

/// A text value's characters, its padding (spaces, NULs) trimmed.
fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes)
        .trim_matches(['\0', ' '])
        .to_string()
}

/// An RLE-encoded frame as `pixels` samples of `width` bytes in the
/// machine's order: one segment a byte of the sample, the most
/// significant first, each PackBits-coded.
fn rle_frame(frame: &[u8], pixels: usize, width: usize) -> Result<Vec<u8>, String> {
    let word = |i: usize| -> Result<usize, String> {
        let b: [u8; 4] = frame
            .get(4 * i..4 * i + 4)
            .and_then(|b| b.try_into().ok())
            .ok_or("its RLE header is cut short")?;
        Ok(u32::from_le_bytes(b) as usize)
    };
    let segments = word(0)?;
    if segments != width {
        return Err(format!(
            "{segments} RLE segments for samples of {width} bytes (one segment a byte)"
        ));
    }
    let mut out = vec![0u8; pixels * width];
    for segment in 0..segments {
        let start = word(1 + segment)?;
        let end = if segment + 1 < segments {
            word(2 + segment)?
        } else {
            frame.len()
        };
        let bytes = frame
            .get(start..end)
            .ok_or_else(|| format!("RLE segment {segment} lies outside its frame"))?;
        let lane = if cfg!(target_endian = "big") {
            segment
        } else {
            width - 1 - segment
        };
        let mut slots = out.iter_mut().skip(lane).step_by(width);
        let mut written = 0;
        let mut i = 0;
        while i < bytes.len() && written < pixels {
            let n = bytes[i] as i8;
            i += 1;
            let (run, repeat): (&[u8], usize) = match n {
                0..=127 => {
                    let run = bytes.get(i..i + n as usize + 1).ok_or_else(|| {
                        format!("RLE segment {segment} ends inside a literal run")
                    })?;
                    i += run.len();
                    (run, 1)
                }
                -127..=-1 => {
                    let run = bytes
                        .get(i..i + 1)
                        .ok_or_else(|| format!("RLE segment {segment} ends inside a repeat"))?;
                    i += 1;
                    (run, (1 - isize::from(n)) as usize)
                }
                // -128: nothing, as the format says.
                _ => (&[], 0),
            };
            for &b in run {
                for _ in 0..repeat {
                    if let Some(slot) = slots.next() {
                        *slot = b;
                        written += 1;
                    }
                }
            }
        }
        if written < pixels {
            return Err(format!(
                "RLE segment {segment} holds {written} of {pixels} pixels"
            ));
        }
    }
    Ok(out)
}

/// A JPEG-coded frame as `columns` x `rows` samples of `width` bytes in
/// the machine's order, its size checked against the header's first.
fn jpeg_frame(frame: &[u8], columns: u32, rows: u32, width: usize) -> Result<Vec<u8>, String> {
    let mut decoder = jpeg_decoder::Decoder::new(frame);
    decoder.set_max_decoding_buffer_size(columns as usize * rows as usize * width);
    decoder.read_info().map_err(|e| format!("JPEG: {e}"))?;
    let info = decoder.info().ok_or("JPEG: no frame header")?;
    let bytes = match info.pixel_format {
        jpeg_decoder::PixelFormat::L8 => 1,
        jpeg_decoder::PixelFormat::L16 => 2,
        other => {
            return Err(format!(
                "JPEG of {other:?} pixels: caveray reads grey images"
            ))
        }
    };
    if (u32::from(info.width), u32::from(info.height), bytes) != (columns, rows, width) {
        return Err(format!(
            "a JPEG frame of {}x{} {bytes}-byte pixels where the header says {columns}x{rows} \
             of {width}",
            info.width, info.height
        ));
    }
    decoder.decode().map_err(|e| format!("JPEG: {e}"))
}
