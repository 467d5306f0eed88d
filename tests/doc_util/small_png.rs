//! Pictures small enough to commit: an RGB image reduced to at most [`MAX_COLOURS`] colours
//! by median cut (Heckbert 1982) and written as an indexed PNG — a fifth of the bytes of
//! the RGB file for the same rendering.

use std::collections::HashMap;
use std::path::Path;

use image::RgbImage;

/// Palette size of the written pictures.
pub const MAX_COLOURS: usize = 256;

/// Writes `img` to `path` as an indexed PNG of at most [`MAX_COLOURS`] colours, through a
/// temporary file renamed into place.
pub fn write_indexed(img: &RgbImage, path: &Path) {
    let pixels: Vec<[u8; 3]> = img.pixels().map(|p| p.0).collect();
    let palette = median_cut(&pixels, MAX_COLOURS);
    let mut nearest: HashMap<[u8; 3], u8> = HashMap::new();
    let indices: Vec<u8> = pixels
        .iter()
        .map(|p| *nearest.entry(*p).or_insert_with(|| closest(&palette, *p)))
        .collect();
    let tmp = path.with_extension("png.tmp");
    let file = std::fs::File::create(&tmp).unwrap_or_else(|e| panic!("{}: {e}", tmp.display()));
    let mut encoder = png::Encoder::new(std::io::BufWriter::new(file), img.width(), img.height());
    encoder.set_color(png::ColorType::Indexed);
    encoder.set_depth(png::BitDepth::Eight);
    encoder.set_palette(palette.concat());
    encoder.set_compression(png::Compression::High);
    let mut writer = encoder.write_header().expect("PNG header");
    writer.write_image_data(&indices).expect("PNG data");
    writer.finish().expect("PNG end");
    std::fs::rename(&tmp, path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
}

/// At most `n` colours standing for `pixels`: the box of colours with the widest channel
/// range is split at its median along that channel (weighted by pixel count) until there are `n` boxes (or none
/// can be split); each box gives its mean colour.
fn median_cut(pixels: &[[u8; 3]], n: usize) -> Vec<[u8; 3]> {
    let mut boxes = vec![pixels.to_vec()];
    while boxes.len() < n {
        let Some((i, channel, range)) = boxes
            .iter()
            .enumerate()
            .map(|(i, b)| {
                let (channel, range) = widest_channel(b);
                (i, channel, range)
            })
            .max_by_key(|&(i, _, range)| (range, std::cmp::Reverse(i)))
        else {
            break;
        };
        if range == 0 {
            break;
        }
        let mut b = boxes.swap_remove(i);
        b.sort_unstable_by_key(|p| p[channel]);
        // Split at the median, between two different values of the channel, so that no
        // colour lands in both halves.
        let median = b[b.len() / 2][channel];
        let mut at = b.partition_point(|p| p[channel] < median);
        if at == 0 {
            at = b.partition_point(|p| p[channel] <= median);
        }
        let upper = b.split_off(at);
        boxes.push(b);
        boxes.push(upper);
    }
    boxes
        .iter()
        .map(|b| {
            let mut sum = [0u64; 3];
            for p in b {
                for c in 0..3 {
                    sum[c] += u64::from(p[c]);
                }
            }
            let len = b.len().max(1) as u64;
            sum.map(|s| u8::try_from((s + len / 2) / len).unwrap_or(u8::MAX))
        })
        .collect()
}

/// The channel whose values spread widest in `pixels`, and that spread.
fn widest_channel(pixels: &[[u8; 3]]) -> (usize, u8) {
    (0..3)
        .map(|c| {
            let (lo, hi) = pixels
                .iter()
                .fold((u8::MAX, 0), |(lo, hi), p| (lo.min(p[c]), hi.max(p[c])));
            (c, hi.saturating_sub(lo))
        })
        .max_by_key(|&(c, range)| (range, std::cmp::Reverse(c)))
        .unwrap_or((0, 0))
}

/// Index of the palette colour nearest to `p` (squared RGB distance).
fn closest(palette: &[[u8; 3]], p: [u8; 3]) -> u8 {
    let dist = |q: &[u8; 3]| -> i32 {
        (0..3)
            .map(|c| (i32::from(q[c]) - i32::from(p[c])).pow(2))
            .sum()
    };
    let best = (0..palette.len())
        .min_by_key(|&i| dist(&palette[i]))
        .unwrap_or(0);
    u8::try_from(best).expect("a palette of at most 256 colours")
}

#[test]
fn few_colours_are_kept_exactly_and_many_are_reduced() {
    let two = [[10, 20, 30], [200, 100, 0], [10, 20, 30]];
    let mut palette = median_cut(&two, MAX_COLOURS);
    palette.sort_unstable();
    assert_eq!(palette, [[10, 20, 30], [200, 100, 0]]);
    let ramp: Vec<[u8; 3]> = (0..=255u8)
        .flat_map(|r| (0..=255u8).map(move |g| [r, g, 7]))
        .collect();
    let palette = median_cut(&ramp, 16);
    assert_eq!(palette.len(), 16);
    // Every colour of the ramp is within a sixteenth of the range of its nearest entry.
    for p in ramp.iter().step_by(97) {
        let q = palette[usize::from(closest(&palette, *p))];
        assert!((0..3).all(|c| q[c].abs_diff(p[c]) <= 40), "{p:?} -> {q:?}");
    }
}
