//! The figure's point labels: what they say (knob values) and where they go (clear of
//! markers, lines and each other).

/// A pixel rectangle, `x1`, `y1` exclusive.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PixelRect {
    pub x0: i32,
    pub y0: i32,
    pub x1: i32,
    pub y1: i32,
}

impl PixelRect {
    pub fn overlaps(&self, o: &PixelRect) -> bool {
        self.x0 < o.x1 && o.x0 < self.x1 && self.y0 < o.y1 && o.y0 < self.y1
    }
    fn inside(&self, o: &PixelRect) -> bool {
        self.x0 >= o.x0 && self.y0 >= o.y0 && self.x1 <= o.x1 && self.y1 <= o.y1
    }
}

/// Places text boxes of `sizes` next to their `anchors` (pixels), in the order given (the
/// first get the best places): the first of eight directions, at three distances from the
/// anchor (`gap` pixels, then 14 and 30 more), whose box stays in `bounds` and overlaps no
/// box placed before and none of `obstacles` (markers, lines). `None` where nothing fits;
/// the `bool` says the box is far enough from its anchor to need a leader line.
pub fn place_labels(
    anchors: &[(i32, i32)],
    sizes: &[(i32, i32)],
    obstacles: &[PixelRect],
    gap: i32,
    bounds: PixelRect,
) -> Vec<Option<(PixelRect, bool)>> {
    let mut placed: Vec<PixelRect> = Vec::new();
    anchors
        .iter()
        .zip(sizes)
        .map(|(&(x, y), &(w, h))| {
            for d in [gap, gap + 14, gap + 30] {
                let candidates = [
                    (x + d, y - h / 2),
                    (x - d - w, y - h / 2),
                    (x - w / 2, y - d - h),
                    (x - w / 2, y + d),
                    (x + d * 2 / 3, y - d * 2 / 3 - h),
                    (x + d * 2 / 3, y + d * 2 / 3),
                    (x - d * 2 / 3 - w, y - d * 2 / 3 - h),
                    (x - d * 2 / 3 - w, y + d * 2 / 3),
                ];
                for (x0, y0) in candidates {
                    let r = PixelRect { x0, y0, x1: x0 + w, y1: y0 + h };
                    if r.inside(&bounds) && !placed.iter().chain(obstacles).any(|o| o.overlaps(&r)) {
                        placed.push(r);
                        return Some((r, d > gap));
                    }
                }
            }
            None
        })
        .collect()
}

/// The label of a point: its knob values (`cube_size=16 cube_precision=half` → `16/half`).
pub(super) fn knob_values(knobs: &str) -> String {
    let values: Vec<&str> = knobs.split_whitespace().filter_map(|kv| kv.split_once('=').map(|(_, v)| v)).collect();
    if values.is_empty() {
        knobs.to_string()
    } else {
        values.join("/")
    }
}

/// `cube_size / cube_precision`: the knob names of `knobs`, or `None` without any.
pub(super) fn knob_names(knobs: &str) -> Option<String> {
    let names: Vec<&str> = knobs.split_whitespace().filter_map(|kv| kv.split_once('=').map(|(k, _)| k)).collect();
    (!names.is_empty()).then(|| names.join(" / "))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn labels_are_placed_without_overlap() {
        // A tight cluster: every label that is placed is inside the bounds, clear of every
        // marker and of every other label; the first, its right blocked by its neighbour's
        // marker, takes the left-hand place.
        let anchors: Vec<(i32, i32)> = (0..12).map(|i| (200 + (i % 4) * 14, 150 + (i / 4) * 12)).collect();
        let markers: Vec<PixelRect> = anchors.iter().map(|&(x, y)| PixelRect { x0: x - 10, y0: y - 10, x1: x + 11, y1: y + 11 }).collect();
        let sizes = vec![(60, 16); anchors.len()];
        let bounds = PixelRect { x0: 0, y0: 0, x1: 400, y1: 300 };
        let places = place_labels(&anchors, &sizes, &markers, 12, bounds);
        assert_eq!(places[0], Some((PixelRect { x0: 128, y0: 142, x1: 188, y1: 158 }, false)));
        // Alone, a point's label goes to its right.
        assert_eq!(
            place_labels(&anchors[..1], &sizes[..1], &markers[..1], 12, bounds)[0],
            Some((PixelRect { x0: 212, y0: 142, x1: 272, y1: 158 }, false))
        );
        let rects: Vec<PixelRect> = places.iter().flatten().map(|(r, _)| *r).collect();
        assert!(rects.len() >= 6, "only {} of 12 placed", rects.len());
        for (i, r) in rects.iter().enumerate() {
            assert!(r.inside(&bounds), "{r:?}");
            assert!(rects[i + 1..].iter().all(|o| !o.overlaps(r)), "{r:?} overlaps another label");
            assert!(markers.iter().all(|m| !r.overlaps(m)), "{r:?} covers a marker");
        }
        // No room at all: nothing is placed.
        assert_eq!(place_labels(&[(5, 5)], &[(60, 16)], &markers, 12, PixelRect { x0: 0, y0: 0, x1: 20, y1: 20 }), [None]);
    }
}
