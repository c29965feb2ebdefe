//! PNG and PGM decoding to a grey raster.

use crate::ImageMapError;

/// A grey image: `gray[y · width + x]`, row `y = 0` at the TOP (as stored in image files).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Raster {
    /// Width, pixels (columns).
    pub width: u32,
    /// Height, pixels (rows).
    pub height: u32,
    /// Grey level of each pixel, 0 black to 255 white; for colour images the mean of R, G and B.
    pub gray: Vec<u8>,
    /// Opacity of each pixel (255 opaque), for images with an alpha channel.
    pub alpha: Option<Vec<u8>>,
}

const PNG_SIGNATURE: &[u8] = b"\x89PNG\r\n\x1a\n";

/// Decodes a PNG or a PGM, told apart by their first bytes.
pub fn decode_image(bytes: &[u8]) -> Result<Raster, ImageMapError> {
    if bytes.starts_with(PNG_SIGNATURE) {
        decode_png(bytes)
    } else if bytes.starts_with(b"P2") || bytes.starts_with(b"P5") {
        decode_pgm(bytes)
    } else {
        Err(ImageMapError::UnknownFormat)
    }
}

fn check_not_empty(width: u32, height: u32) -> Result<(), ImageMapError> {
    if width == 0 || height == 0 {
        return Err(ImageMapError::Empty { width, height });
    }
    Ok(())
}

/// Width and height of a PNG or PGM from its header alone (nothing is decoded), so that a
/// caller can refuse an image too large for its memory budget before allocating anything.
pub fn image_size(bytes: &[u8]) -> Result<(u32, u32), ImageMapError> {
    if bytes.starts_with(PNG_SIGNATURE) {
        // The IHDR chunk comes first: length, "IHDR", width, height (big-endian).
        let field = |at: usize| {
            bytes
                .get(at..at + 4)
                .map(|b| u32::from_be_bytes([b[0], b[1], b[2], b[3]]))
        };
        match (bytes.get(12..16), field(16), field(20)) {
            (Some(b"IHDR"), Some(w), Some(h)) => Ok((w, h)),
            _ => Err(ImageMapError::Png("no IHDR chunk where PNG puts it".into())),
        }
    } else if bytes.starts_with(b"P2") || bytes.starts_with(b"P5") {
        let mut h = Header { bytes, pos: 2 };
        let width = h.number("width")?;
        let height = h.number("height")?;
        Ok((width, height))
    } else {
        Err(ImageMapError::UnknownFormat)
    }
}

/// Decodes a PNG of any colour type and bit depth (palettes expanded, 16 bits reduced to 8).
/// Non-interlaced images are decoded row by row: the decoder adds one row's buffer, so the grey
/// raster (one byte per pixel, plus alpha when the image has it) is the only full-size copy.
pub fn decode_png(bytes: &[u8]) -> Result<Raster, ImageMapError> {
    let err = |e: png::DecodingError| ImageMapError::Png(e.to_string());
    let mut decoder = png::Decoder::new(std::io::Cursor::new(bytes));
    decoder.set_transformations(png::Transformations::normalize_to_color8());
    let mut reader = decoder.read_info().map_err(err)?;
    let (width, height, interlaced) = {
        let info = reader.info();
        (info.width, info.height, info.interlaced)
    };
    check_not_empty(width, height)?;
    let (color_type, _) = reader.output_color_type();
    let channels = color_type.samples();
    let (w, h) = (width as usize, height as usize);
    let mut gray = Vec::with_capacity(w * h);
    let has_alpha = matches!(
        color_type,
        png::ColorType::GrayscaleAlpha | png::ColorType::Rgba
    );
    let mut alpha = has_alpha.then(|| Vec::with_capacity(w * h));
    let mut push_line = |line: &[u8]| {
        for px in line[..w * channels].chunks_exact(channels) {
            let color = if channels >= 3 { &px[..3] } else { &px[..1] };
            let sum: u32 = color.iter().map(|&v| u32::from(v)).sum();
            let n = color.len() as u32;
            gray.push(((sum + n / 2) / n) as u8);
            if let Some(a) = alpha.as_mut() {
                a.push(px[channels - 1]);
            }
        }
    };
    if interlaced {
        let size = reader
            .output_buffer_size()
            .ok_or_else(|| ImageMapError::Png("the image is too large".into()))?;
        let mut buf = vec![0; size];
        let info = reader.next_frame(&mut buf).map_err(err)?;
        for y in 0..h {
            push_line(&buf[y * info.line_size..(y + 1) * info.line_size]);
        }
    } else {
        for _ in 0..h {
            let row = reader
                .next_row()
                .map_err(err)?
                .ok_or_else(|| ImageMapError::Png("fewer rows than the header says".into()))?;
            if row.data().len() < w * channels {
                return Err(ImageMapError::Png(
                    "a row shorter than the header says".into(),
                ));
            }
            push_line(row.data());
        }
    }
    Ok(Raster {
        width,
        height,
        gray,
        alpha,
    })
}

/// Reads PGM header tokens, skipping whitespace and `#` comments.
struct Header<'a> {
    bytes: &'a [u8],
    pos: usize,
}

impl Header<'_> {
    fn skip_space(&mut self) {
        while let Some(&b) = self.bytes.get(self.pos) {
            if b == b'#' {
                while self.bytes.get(self.pos).is_some_and(|&c| c != b'\n') {
                    self.pos += 1;
                }
            } else if b.is_ascii_whitespace() {
                self.pos += 1;
            } else {
                break;
            }
        }
    }

    fn number(&mut self, field: &'static str) -> Result<u32, ImageMapError> {
        self.skip_space();
        let start = self.pos;
        while self.bytes.get(self.pos).is_some_and(u8::is_ascii_digit) {
            self.pos += 1;
        }
        let text = std::str::from_utf8(&self.bytes[start..self.pos]).unwrap_or("");
        text.parse::<u32>().map_err(|_| ImageMapError::Pgm {
            field,
            message: format!(
                "expected a whole number at byte {start}, found {:?}",
                String::from_utf8_lossy(&self.bytes[start..(start + 8).min(self.bytes.len())])
            ),
        })
    }
}

/// Decodes a PGM (`P2` plain or `P5` binary; 8- or 16-bit), scaling grey levels to 0–255.
///
/// ```
/// let raster = skyplan_imagemap::decode_pgm(b"P5 2 1 255\n\x00\xff")?;
/// assert_eq!((raster.width, raster.height, raster.gray.as_slice()), (2, 1, &[0u8, 255][..]));
/// # Ok::<(), skyplan_imagemap::ImageMapError>(())
/// ```
pub fn decode_pgm(bytes: &[u8]) -> Result<Raster, ImageMapError> {
    let binary = match bytes.get(..2) {
        Some(b"P5") => true,
        Some(b"P2") => false,
        _ => {
            return Err(ImageMapError::Pgm {
                field: "magic",
                message: "expected `P2` or `P5`".into(),
            });
        }
    };
    let mut h = Header { bytes, pos: 2 };
    let width = h.number("width")?;
    let height = h.number("height")?;
    let maxval = h.number("maxval")?;
    if !(1..=65535).contains(&maxval) {
        return Err(ImageMapError::Pgm {
            field: "maxval",
            message: format!("expected 1..=65535, found {maxval}"),
        });
    }
    check_not_empty(width, height)?;
    let count = width as usize * height as usize;
    let scale = |v: u32| -> Result<u8, ImageMapError> {
        if v > maxval {
            return Err(ImageMapError::Pgm {
                field: "pixels",
                message: format!("value {v} exceeds maxval {maxval}"),
            });
        }
        Ok(((v * 255 + maxval / 2) / maxval) as u8)
    };
    // Never trust the header for an allocation: no more values than bytes.
    let mut gray = Vec::with_capacity(count.min(bytes.len()));
    if binary {
        // Exactly one whitespace byte separates the header from the pixels.
        let start = h.pos + 1;
        let per = if maxval < 256 { 1 } else { 2 };
        let data = bytes.get(start..).unwrap_or(&[]);
        if data.len() < count * per {
            return Err(ImageMapError::Pgm {
                field: "pixels",
                message: format!(
                    "expected {} bytes for {width} × {height} pixels, found {}",
                    count * per,
                    data.len()
                ),
            });
        }
        for px in data[..count * per].chunks_exact(per) {
            let v = px.iter().fold(0u32, |acc, &b| (acc << 8) | u32::from(b));
            gray.push(scale(v)?);
        }
    } else {
        for k in 0..count {
            h.skip_space();
            if h.pos >= bytes.len() {
                return Err(ImageMapError::Pgm {
                    field: "pixels",
                    message: format!("expected {count} values, found {k}"),
                });
            }
            gray.push(scale(h.number("pixels")?)?);
        }
    }
    Ok(Raster {
        width,
        height,
        gray,
        alpha: None,
    })
}
