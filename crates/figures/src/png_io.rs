//! PNG in memory with the `png` crate: the encoder settings are explicit (so
//! the bytes are fixed for one crate version), and the decoder gives back the
//! pixels a snapshot hashes, whatever encoder wrote the file.

/// Encoder settings. The default is what the pipeline writes.
#[derive(Debug, Clone, Copy)]
pub struct PngSettings {
    pub compression: png::Compression,
    pub filter: png::FilterType,
}

impl Default for PngSettings {
    fn default() -> Self {
        PngSettings { compression: png::Compression::Default, filter: png::FilterType::Sub }
    }
}

/// Encodes RGB8 pixels (row-major, `size.0 * size.1 * 3` bytes) as PNG.
pub fn encode_png(size: (u32, u32), rgb: &[u8], settings: PngSettings) -> Result<Vec<u8>, String> {
    let expected = size.0 as usize * size.1 as usize * 3;
    if rgb.len() != expected {
        return Err(format!("{} RGB bytes for a {}x{} image, expected {expected}", rgb.len(), size.0, size.1));
    }
    let mut out = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut out, size.0, size.1);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        enc.set_compression(settings.compression);
        enc.set_filter(settings.filter);
        enc.set_adaptive_filter(png::AdaptiveFilterType::NonAdaptive);
        let mut w = enc.write_header().map_err(|e| e.to_string())?;
        w.write_image_data(rgb).map_err(|e| e.to_string())?;
        w.finish().map_err(|e| e.to_string())?;
    }
    Ok(out)
}

/// Decodes an 8-bit RGB or RGBA PNG to ((width, height), RGB8 pixels); alpha
/// is dropped (figures are opaque). Other colour types are an error.
pub fn decode_png(bytes: &[u8]) -> Result<((u32, u32), Vec<u8>), String> {
    let mut reader = png::Decoder::new(std::io::Cursor::new(bytes)).read_info().map_err(|e| e.to_string())?;
    let mut buf = vec![0u8; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).map_err(|e| e.to_string())?;
    buf.truncate(info.buffer_size());
    if info.bit_depth != png::BitDepth::Eight {
        return Err(format!("bit depth {:?}, expected 8", info.bit_depth));
    }
    let rgb = match info.color_type {
        png::ColorType::Rgb => buf,
        png::ColorType::Rgba => buf.chunks_exact(4).flat_map(|p| [p[0], p[1], p[2]]).collect(),
        other => return Err(format!("colour type {other:?}, expected RGB or RGBA")),
    };
    Ok(((info.width, info.height), rgb))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_keeps_pixels() {
        let rgb: Vec<u8> = (0..4 * 3 * 3).map(|i| (i * 7) as u8).collect();
        let png = encode_png((4, 3), &rgb, PngSettings::default()).unwrap();
        assert_eq!(decode_png(&png).unwrap(), ((4, 3), rgb));
        assert!(encode_png((4, 4), &[0; 3], PngSettings::default()).is_err());
    }
}
