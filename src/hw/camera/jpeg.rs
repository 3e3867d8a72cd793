//! Checking JPEG data before OpenCV decodes it. libjpeg decodes a cut or
//! corrupt file anyway, greying or garbling what it could not read, and
//! warns on stderr without the file's name. So the markers are walked to
//! the end-of-image marker, skipping each segment by its length (an EXIF
//! thumbnail's own end marker does not count), and the scans of a
//! sequential Huffman JPEG (what cameras and OpenCV write) are followed
//! code by code, block by block, as libjpeg reads them, without the
//! arithmetic of decoding: a bad Huffman code, a marker before the last
//! block (libjpeg's "premature end of data segment"), bytes left over
//! after it ("extraneous bytes before marker") or a missing restart marker
//! is corruption. Progressive and arithmetic-coded scans are only walked.

/// What is wrong with JPEG data.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum JpegFault {
    /// The data stops before its end-of-image marker.
    Truncated,
    /// The data runs to its end but does not decode: what is wrong.
    Corrupt(String),
}

type Checked<T> = Result<T, JpegFault>;

const SOI: [u8; 2] = [0xFF, 0xD8];
const EOI: u8 = 0xD9;
const RST0: u8 = 0xD0;

/// Checks JPEG data; data that does not start like a JPEG is not judged.
pub fn check(bytes: &[u8]) -> Checked<()> {
    if !bytes.starts_with(&SOI) {
        return Ok(());
    }
    let mut at = SOI.len();
    // The frame of a sequential Huffman JPEG, the only kind whose scans are
    // followed; `None` until its SOF, and for other kinds.
    let mut frame = None;
    let mut tables = HuffmanTables::default();
    let mut restart_interval = 0;
    loop {
        let marker = next_marker(bytes, &mut at)?;
        match marker {
            EOI => return Ok(()),
            // Markers without a segment.
            0x01 | 0xD0..=0xD8 => continue,
            _ => {}
        }
        let segment = segment(bytes, &mut at)?;
        match marker {
            0xC0 | 0xC1 => frame = Frame::parse(segment)?,
            0xC2 | 0xC3 | 0xC5..=0xC7 | 0xC9..=0xCB | 0xCD..=0xCF => frame = None,
            0xC4 => tables.define(segment)?,
            0xDD => restart_interval = usize::from(be16(segment, 0)?),
            0xDA => match &frame {
                Some(frame) => {
                    let scan = Scan::parse(segment, frame, &tables)?;
                    at = scan.follow(bytes, at, restart_interval)?;
                }
                None => at = skip_entropy_coded(bytes, at),
            },
            _ => {}
        }
    }
}

/// The next marker's code, after optional fill bytes; `at` is left after
/// it. Other bytes before it (a stuffed 0xFF 0x00 among them) are
/// corruption, as libjpeg warns.
fn next_marker(bytes: &[u8], at: &mut usize) -> Checked<u8> {
    let mut extraneous = 0;
    loop {
        while byte(bytes, *at)? != 0xFF {
            *at += 1;
            extraneous += 1;
        }
        while byte(bytes, *at)? == 0xFF {
            *at += 1;
        }
        let marker = byte(bytes, *at)?;
        *at += 1;
        if marker == 0x00 {
            extraneous += 2;
            continue;
        }
        if extraneous > 0 {
            return Err(JpegFault::Corrupt(format!(
                "{extraneous} extraneous bytes before marker 0x{marker:02X}"
            )));
        }
        return Ok(marker);
    }
}

/// The segment at `at` (its length, then its data), whose data is returned;
/// `at` is left after it.
fn segment<'a>(bytes: &'a [u8], at: &mut usize) -> Checked<&'a [u8]> {
    let length = usize::from(be16(bytes.get(*at..).unwrap_or_default(), 0)?);
    if length < 2 {
        return Err(JpegFault::Corrupt(format!("a segment of length {length}")));
    }
    let data = bytes
        .get(*at + 2..*at + length)
        .ok_or(JpegFault::Truncated)?;
    *at += length;
    Ok(data)
}

fn be16(bytes: &[u8], at: usize) -> Checked<u16> {
    match bytes.get(at..at + 2) {
        Some(&[high, low]) => Ok(u16::from_be_bytes([high, low])),
        _ => Err(JpegFault::Truncated),
    }
}

fn byte(bytes: &[u8], at: usize) -> Checked<u8> {
    bytes.get(at).copied().ok_or(JpegFault::Truncated)
}

/// Skips entropy-coded data not followed (in which 0xFF is always followed
/// by 0x00, a restart marker or fill): the position of the marker after it.
fn skip_entropy_coded(bytes: &[u8], mut at: usize) -> usize {
    while at + 1 < bytes.len() {
        match (bytes[at], bytes[at + 1]) {
            (0xFF, 0x00 | RST0..=0xD7) => at += 2,
            (0xFF, _) => return at,
            _ => at += 1,
        }
    }
    bytes.len()
}

fn corrupt<T>(message: &str) -> Checked<T> {
    Err(JpegFault::Corrupt(message.to_owned()))
}

/// A frame's size and its components' sampling factors.
struct Frame {
    width: usize,
    height: usize,
    /// Each component's id and its horizontal and vertical sampling.
    components: Vec<(u8, usize, usize)>,
}

impl Frame {
    /// A frame whose scans can be followed; `None` for one whose height
    /// comes later (a DNL marker), which is only walked.
    fn parse(segment: &[u8]) -> Checked<Option<Frame>> {
        let height = usize::from(be16(segment, 1)?);
        let width = usize::from(be16(segment, 3)?);
        let count = usize::from(byte(segment, 5)?);
        if width == 0 || count == 0 {
            return corrupt("a frame without width or components");
        }
        let components = (0..count)
            .map(|k| {
                let sampling = byte(segment, 7 + 3 * k)?;
                let (h, v) = (usize::from(sampling >> 4), usize::from(sampling & 0x0F));
                if !(1..=4).contains(&h) || !(1..=4).contains(&v) {
                    return corrupt("a sampling factor outside 1..4");
                }
                Ok((byte(segment, 6 + 3 * k)?, h, v))
            })
            .collect::<Checked<Vec<_>>>()?;
        Ok((height > 0).then_some(Frame {
            width,
            height,
            components,
        }))
    }
}

/// A Huffman table as JPEG's decoding procedure uses it (ITU T.81 F.2.2.3):
/// per code length, the largest code, and where its values start.
#[derive(Clone)]
struct Huffman {
    /// Indexed by length 1..=16; -1 where no code has that length.
    max_code: [i32; 17],
    /// The first code of each length, and its value's index.
    min_code: [i32; 17],
    first_value: [usize; 17],
    values: Vec<u8>,
}

impl Huffman {
    fn new(counts: &[u8], values: &[u8]) -> Checked<Huffman> {
        let mut table = Huffman {
            max_code: [-1; 17],
            min_code: [0; 17],
            first_value: [0; 17],
            values: values.to_vec(),
        };
        let (mut code, mut index) = (0i32, 0usize);
        for length in 1..=16 {
            let count = usize::from(counts[length - 1]);
            if count > 0 {
                table.first_value[length] = index;
                table.min_code[length] = code;
                code += count as i32;
                index += count;
                table.max_code[length] = code - 1;
                if code > 1 << length {
                    return corrupt("a Huffman table with more codes than bits");
                }
            }
            code <<= 1;
        }
        Ok(table)
    }
}

#[derive(Default)]
struct HuffmanTables {
    dc: [Option<Huffman>; 4],
    ac: [Option<Huffman>; 4],
}

impl HuffmanTables {
    /// Defines the tables of a DHT segment.
    fn define(&mut self, mut segment: &[u8]) -> Checked<()> {
        while let Some((&class_id, rest)) = segment.split_first() {
            let counts = rest.get(..16).ok_or(JpegFault::Truncated)?;
            let total: usize = counts.iter().map(|&c| usize::from(c)).sum();
            let values = rest.get(16..16 + total).ok_or(JpegFault::Truncated)?;
            let table = Some(Huffman::new(counts, values)?);
            match (class_id >> 4, usize::from(class_id & 0x0F)) {
                (0, id @ 0..=3) => self.dc[id] = table,
                (1, id @ 0..=3) => self.ac[id] = table,
                _ => return corrupt("a Huffman table of no class or id"),
            }
            segment = &rest[16 + total..];
        }
        Ok(())
    }
}

/// A scan of a sequential Huffman frame: its components' tables and how
/// many blocks each contributes to a unit (MCU), and how many units.
struct Scan<'a> {
    /// Per component: DC table, AC table, blocks per unit.
    components: Vec<(&'a Huffman, &'a Huffman, usize)>,
    units: usize,
}

impl<'a> Scan<'a> {
    fn parse(segment: &[u8], frame: &Frame, tables: &'a HuffmanTables) -> Checked<Scan<'a>> {
        let count = usize::from(byte(segment, 0)?);
        let h_max = frame.components.iter().map(|c| c.1).max().unwrap_or(1);
        let v_max = frame.components.iter().map(|c| c.2).max().unwrap_or(1);
        let blocks_across =
            |pixels: usize, factor: usize, max: usize| (pixels * factor).div_ceil(max).div_ceil(8);
        let mut components = Vec::with_capacity(count);
        let mut units = frame
            .width
            .div_ceil(8 * h_max)
            .saturating_mul(frame.height.div_ceil(8 * v_max));
        for k in 0..count {
            let id = byte(segment, 1 + 2 * k)?;
            let selectors = byte(segment, 2 + 2 * k)?;
            let Some(&(_, h, v)) = frame.components.iter().find(|c| c.0 == id) else {
                return corrupt("a scan of a component the frame lacks");
            };
            let dc = tables
                .dc
                .get(usize::from(selectors >> 4))
                .and_then(Option::as_ref);
            let ac = tables
                .ac
                .get(usize::from(selectors & 0x0F))
                .and_then(Option::as_ref);
            let (Some(dc), Some(ac)) = (dc, ac) else {
                return corrupt("a scan with an undefined Huffman table");
            };
            if count == 1 {
                // A scan of one component codes its blocks one by one.
                units = blocks_across(frame.width, h, h_max).saturating_mul(blocks_across(
                    frame.height,
                    v,
                    v_max,
                ));
                components.push((dc, ac, 1));
            } else {
                components.push((dc, ac, h * v));
            }
        }
        if count == 0 {
            return corrupt("a scan of no component");
        }
        Ok(Scan { components, units })
    }

    /// Follows the scan's entropy-coded data from `at`, unit by unit (a
    /// restart marker after every `restart_interval` of them, if not 0):
    /// the position after its last byte.
    fn follow(&self, bytes: &[u8], at: usize, restart_interval: usize) -> Checked<usize> {
        let mut bits = BitReader {
            bytes,
            at,
            byte: 0,
            left: 0,
        };
        for unit in 0..self.units {
            if restart_interval > 0 && unit > 0 && unit % restart_interval == 0 {
                bits.restart((unit / restart_interval - 1) % 8)?;
            }
            for &(dc, ac, blocks) in &self.components {
                for _ in 0..blocks {
                    bits.block(dc, ac)?;
                }
            }
        }
        Ok(bits.at)
    }
}

/// Bits of entropy-coded data, most significant first, with the 0x00
/// after each 0xFF data byte removed.
struct BitReader<'a> {
    bytes: &'a [u8],
    /// The next byte to load.
    at: usize,
    byte: u8,
    /// Bits of `byte` not yet read.
    left: u32,
}

impl BitReader<'_> {
    fn bit(&mut self) -> Checked<u16> {
        if self.left == 0 {
            let byte = byte(self.bytes, self.at)?;
            if byte == 0xFF {
                match byte_after_fill(self.bytes, self.at + 1)? {
                    0x00 => self.at += 1,
                    _ => return corrupt("premature end of data segment"),
                }
            }
            self.at += 1;
            self.byte = byte;
            self.left = 8;
        }
        self.left -= 1;
        Ok(u16::from(self.byte >> self.left) & 1)
    }

    /// Skips `count` bits (a coefficient's value, unread).
    fn skip(&mut self, count: u8) -> Checked<()> {
        for _ in 0..count {
            self.bit()?;
        }
        Ok(())
    }

    fn decode(&mut self, table: &Huffman) -> Checked<u8> {
        let mut code = 0;
        for length in 1..=16 {
            code = (code << 1) | i32::from(self.bit()?);
            if code <= table.max_code[length] {
                let index = table.first_value[length] + (code - table.min_code[length]) as usize;
                return table
                    .values
                    .get(index)
                    .copied()
                    .ok_or(JpegFault::Corrupt("bad Huffman code".into()));
            }
        }
        corrupt("bad Huffman code")
    }

    /// One 8×8 block: its DC difference, then its AC coefficients run by
    /// run to the end-of-block code or the 63rd.
    fn block(&mut self, dc: &Huffman, ac: &Huffman) -> Checked<()> {
        let size = self.decode(dc)?;
        if size > 16 {
            return corrupt("a DC difference of more than 16 bits");
        }
        self.skip(size)?;
        let mut k = 1;
        while k < 64 {
            let run_size = self.decode(ac)?;
            let (run, size) = (run_size >> 4, run_size & 0x0F);
            if size == 0 && run != 15 {
                return Ok(());
            }
            k += usize::from(run) + 1;
            self.skip(size)?;
        }
        if k > 64 {
            return corrupt("AC coefficients past the end of a block");
        }
        Ok(())
    }

    /// Drops the rest of the byte and reads restart marker `index` (0..8).
    fn restart(&mut self, index: usize) -> Checked<()> {
        self.left = 0;
        let marker = next_marker(self.bytes, &mut self.at)?;
        if usize::from(marker) != usize::from(RST0) + index {
            return Err(JpegFault::Corrupt(format!(
                "found marker 0x{marker:02X} instead of RST{index}"
            )));
        }
        Ok(())
    }
}

/// The first byte from `at` that is not a fill byte (0xFF).
fn byte_after_fill(bytes: &[u8], mut at: usize) -> Checked<u8> {
    while byte(bytes, at)? == 0xFF {
        at += 1;
    }
    byte(bytes, at)
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;
    use opencv::core::{CV_8UC1, CV_8UC3, Mat, Scalar, Vector};
    use opencv::imgcodecs;
    use opencv::prelude::*;

    /// A small noisy colour JPEG as OpenCV writes it (4:2:0), with
    /// `params` (pairs of `IMWRITE_*` and value).
    pub(in crate::hw::camera) fn jpeg_bytes(params: &[i32]) -> Vec<u8> {
        noisy_jpeg(CV_8UC3, params)
    }

    /// A small noisy JPEG of pixel type `typ`.
    fn noisy_jpeg(typ: i32, params: &[i32]) -> Vec<u8> {
        let mut image =
            Mat::new_rows_cols_with_default(24, 32, typ, Scalar::all(0.0)).expect("image");
        opencv::core::randu(&mut image, &Scalar::all(0.0), &Scalar::all(255.0)).expect("noise");
        let mut bytes = Vector::<u8>::new();
        let params = Vector::from_slice(params);
        assert!(imgcodecs::imencode(".jpg", &image, &mut bytes, &params).expect("encode"));
        bytes.to_vec()
    }

    /// Where the entropy-coded data of the first scan starts.
    pub(in crate::hw::camera) fn scan_data_start(bytes: &[u8]) -> usize {
        let sos = bytes
            .windows(2)
            .position(|w| w == [0xFF, 0xDA])
            .expect("a scan");
        sos + 2 + usize::from(u16::from_be_bytes([bytes[sos + 2], bytes[sos + 3]]))
    }

    #[test]
    fn whole_jpegs_pass_and_every_cut_is_truncated() {
        for (typ, params) in [
            (CV_8UC3, &[][..]),
            (CV_8UC1, &[]),
            (CV_8UC3, &[imgcodecs::IMWRITE_JPEG_RST_INTERVAL, 2]),
            (CV_8UC3, &[imgcodecs::IMWRITE_JPEG_PROGRESSIVE, 1]),
        ] {
            let bytes = noisy_jpeg(typ, params);
            assert_eq!(check(&bytes), Ok(()), "{params:?}");
            for cut in 2..bytes.len() {
                assert_eq!(
                    check(&bytes[..cut]),
                    Err(JpegFault::Truncated),
                    "{params:?}: cut at {cut} of {}",
                    bytes.len()
                );
            }
        }
    }

    #[test]
    fn data_after_the_end_and_a_thumbnail_s_end_marker_are_told_apart() {
        let bytes = jpeg_bytes(&[]);
        let mut trailing = bytes.clone();
        trailing.extend_from_slice(b"camera maker's trailer");
        assert_eq!(check(&trailing), Ok(()));

        // An APP1 segment holding a whole JPEG (as an EXIF thumbnail does),
        // in front of a truncated main image.
        let thumbnail = jpeg_bytes(&[]);
        let length = u16::try_from(thumbnail.len() + 2).expect("fits");
        let mut with_thumbnail = vec![0xFF, 0xD8, 0xFF, 0xE1];
        with_thumbnail.extend_from_slice(&length.to_be_bytes());
        with_thumbnail.extend_from_slice(&thumbnail);
        with_thumbnail.extend_from_slice(&bytes[2..]);
        assert_eq!(check(&with_thumbnail), Ok(()));
        with_thumbnail.truncate(with_thumbnail.len() - 100);
        assert_eq!(check(&with_thumbnail), Err(JpegFault::Truncated));
    }

    #[test]
    fn corrupt_scan_data_is_found() {
        let bytes = jpeg_bytes(&[]);
        let start = scan_data_start(&bytes);
        let middle = (start + bytes.len()) / 2;
        // An end-of-image marker in the middle of the scan: libjpeg's
        // "premature end of data segment".
        let mut early_end = bytes.clone();
        early_end[middle..middle + 2].copy_from_slice(&[0xFF, EOI]);
        assert_eq!(
            check(&early_end),
            Err(JpegFault::Corrupt("premature end of data segment".into()))
        );
        // Bytes overwritten: some code goes wrong, or the blocks end
        // before or after the data does.
        let mut found = 0;
        for seed in 0..20u8 {
            let mut garbled = bytes.clone();
            for (k, byte) in garbled[middle..middle + 16].iter_mut().enumerate() {
                *byte = seed
                    .wrapping_mul(37)
                    .wrapping_add((k as u8).wrapping_mul(101))
                    & 0x7F;
            }
            if garbled != bytes {
                found += usize::from(matches!(check(&garbled), Err(JpegFault::Corrupt(_))));
            }
        }
        assert!(found >= 18, "{found} of 20 garbled scans found corrupt");
        // Extra bytes between the scan and the end-of-image marker.
        let mut extra = bytes[..bytes.len() - 2].to_vec();
        extra.extend_from_slice(&[0x12, 0x34, 0xFF, EOI]);
        assert_eq!(
            check(&extra),
            Err(JpegFault::Corrupt(
                "2 extraneous bytes before marker 0xD9".into()
            ))
        );
    }

    #[test]
    fn a_missing_restart_marker_is_corrupt() {
        let bytes = jpeg_bytes(&[imgcodecs::IMWRITE_JPEG_RST_INTERVAL, 2]);
        let start = scan_data_start(&bytes);
        let rst = start
            + bytes[start..]
                .windows(2)
                .position(|w| w == [0xFF, RST0])
                .expect("a restart marker");
        let mut wrong = bytes.clone();
        wrong[rst + 1] = RST0 + 3;
        assert_eq!(
            check(&wrong),
            Err(JpegFault::Corrupt(
                "found marker 0xD3 instead of RST0".into()
            ))
        );
    }

    #[test]
    fn data_that_is_no_jpeg_is_not_judged() {
        assert_eq!(check(b"\x89PNG\r\n"), Ok(()));
        assert_eq!(check(b""), Ok(()));
    }
}
