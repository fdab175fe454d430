//! The figures of one scene from the bench's log: pass and frame medians,
//! exact overdraw from the read-back counts, and the pixel comparisons of
//! the box variants (see the docs of `splat.rs`).

use super::*;

fn median(values: &[f64]) -> f64 {
    if values.is_empty() {
        return f64::NAN;
    }
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// `(fragments, pixels with at least one, largest count)` of an overdraw
/// read-back.
fn fragment_counts(pixels: &[[f32; 4]]) -> (u64, u64, u64) {
    let mut total = 0;
    let mut touched = 0;
    let mut max = 0;
    for p in pixels {
        let k = (f64::from(p[0]) * 64.0).round() as u64;
        total += k;
        touched += u64::from(k > 0);
        max = max.max(k);
    }
    (total, touched, max)
}

/// Whether a `QuadricIds` pixel shows the solid (the background is black).
fn shows_solid(p: &[f32; 4]) -> bool {
    p[..3].iter().any(|&c| c > 0.0)
}

/// Medians and overdraw of one scene.
pub(super) struct SceneFigures {
    pub(super) pass_ms: HashMap<Variant, f64>,
    pub(super) frame_minus_empty_ms: HashMap<Variant, f64>,
    /// The boxes on the multisampled camera (`CHISEL_BENCH_MSAA`): its
    /// samples, the pass median (ms) and the frame median less the empty
    /// frame's at the same samples.
    pub(super) msaa_boxes: Option<MsaaFigures>,
    /// Fragments per covered pixel (exact) and the adapter's fragment
    /// shader invocations per covered pixel.
    pub(super) overdraw: HashMap<Variant, (f64, f64)>,
    /// Fragments per covered pixel that pass the depth test after a depth
    /// prepass (`SplatOutput::DepthTestedOverdraw`, exact).
    pub(super) depth_tested: HashMap<Variant, f64>,
    pub(super) covered: u64,
    /// Pixels whose quadric ids differ between cell and sphere boxes:
    /// `(x, y, solid with cell boxes, solid with sphere boxes)`.
    pub(super) sphere_differ: Vec<(u32, u32, bool, bool)>,
}

/// The boxes' figures on a multisampled camera.
#[derive(Clone, Copy)]
pub(super) struct MsaaFigures {
    pub(super) samples: u32,
    pub(super) pass_ms: f64,
    pub(super) frame_minus_empty_ms: f64,
}

pub(super) fn figures(log: &Log) -> SceneFigures {
    let median_of = |values: Option<&Vec<f64>>| median(values.map_or(&[][..], Vec::as_slice));
    let empty = median_of(log.frame_ms.get(&(Draw::Empty, 1)));
    let all = [
        Variant::Boxes,
        Variant::OpenBoxes,
        Variant::Quads,
        Variant::Global,
    ];
    let msaa = log
        .frame_ms
        .keys()
        .map(|&(_, samples)| samples)
        .find(|&samples| samples > 1);
    let drawings = all
        .map(|v| (Draw::Prop(v), 1))
        .into_iter()
        .chain([(Draw::Empty, 1)])
        .chain(msaa.into_iter().flat_map(|samples| {
            [
                (Draw::Prop(Variant::Boxes), samples),
                (Draw::Empty, samples),
            ]
        }));
    for key in drawings {
        let pass = log.pass_ms.get(&key).cloned().unwrap_or_default();
        let frame = log.frame_ms.get(&key).cloned().unwrap_or_default();
        let (draw, samples) = key;
        println!(
            "  {draw:?}, {samples} sample(s): pass median {:.2} ms of {:.1?}; frame median {:.1} \
             ms of {:.0?}",
            median(&pass),
            pass,
            median(&frame),
            frame,
        );
    }
    let msaa_boxes = msaa.map(|samples| MsaaFigures {
        samples,
        pass_ms: median_of(log.pass_ms.get(&(Draw::Prop(Variant::Boxes), samples))),
        frame_minus_empty_ms: median_of(log.frame_ms.get(&(Draw::Prop(Variant::Boxes), samples)))
            - median_of(log.frame_ms.get(&(Draw::Empty, samples))),
    });
    let ids = |variant| log.images.get(&(variant, SplatOutput::QuadricIds));
    let covered = ids(Variant::Boxes).map_or(0, |image| {
        image.iter().filter(|p| shows_solid(p)).count() as u64
    });
    if let (Some(closed), Some(open)) = (ids(Variant::Boxes), ids(Variant::OpenBoxes)) {
        let differ = closed.iter().zip(open).filter(|(a, b)| a != b).count();
        let holes = closed
            .iter()
            .zip(open)
            .filter(|(a, b)| shows_solid(a) && !shows_solid(b))
            .count();
        println!("  open boxes against closed, quadric ids: {differ} pixels differ, {holes} holes");
    }
    let mut sphere_differ = Vec::new();
    for (other, what) in [
        (Variant::UnculledBoxes, "culled against unculled boxes"),
        (Variant::SphereBoxes, "cell boxes against sphere boxes"),
    ] {
        if let (Some(boxes), Some(image)) = (ids(Variant::Boxes), ids(other)) {
            let differ: Vec<usize> = (0..boxes.len()).filter(|&i| boxes[i] != image[i]).collect();
            let only = |a: &[[f32; 4]], b: &[[f32; 4]]| {
                differ
                    .iter()
                    .filter(|&&i| shows_solid(&a[i]) && !shows_solid(&b[i]))
                    .count()
            };
            println!(
                "  {what}, quadric ids: {} pixels differ ({} solid only with the first, {} only \
                 with the second)",
                differ.len(),
                only(boxes, image),
                only(image, boxes),
            );
            if other == Variant::SphereBoxes {
                sphere_differ = differ
                    .iter()
                    .map(|&i| {
                        let (x, y) = ((i % WIDTH as usize) as u32, (i / WIDTH as usize) as u32);
                        (x, y, shows_solid(&boxes[i]), shows_solid(&image[i]))
                    })
                    .collect();
            }
        }
    }
    let mut overdraw = HashMap::new();
    let mut depth_tested = HashMap::new();
    for variant in [Variant::Boxes, Variant::SphereBoxes] {
        let Some(image) = log.images.get(&(variant, SplatOutput::DepthTestedOverdraw)) else {
            continue;
        };
        let (total, touched, max) = fragment_counts(image);
        println!(
            "  {variant:?} depth-tested overdraw (after a depth prepass): {total} fragments on \
             {touched} pixels (max {max}): {:.2} per covered pixel",
            total as f64 / covered as f64,
        );
        depth_tested.insert(variant, total as f64 / covered as f64);
    }
    for variant in all
        .into_iter()
        .chain([Variant::UnculledBoxes, Variant::SphereBoxes])
    {
        let key = (variant, SplatOutput::Overdraw);
        let Some(image) = log.images.get(&key) else {
            continue;
        };
        let (total, touched, max) = fragment_counts(image);
        let invocations = median_of(log.invocations.get(&key));
        println!(
            "  {variant:?} overdraw: {total} fragments on {touched} pixels (max {max}), \
             {covered} covered pixels: {:.2} per covered pixel; \
             {invocations} fragment shader invocations (pipeline statistics)",
            total as f64 / covered as f64,
        );
        overdraw.insert(
            variant,
            (total as f64 / covered as f64, invocations / covered as f64),
        );
    }
    SceneFigures {
        pass_ms: all
            .into_iter()
            .map(|v| (v, median_of(log.pass_ms.get(&(Draw::Prop(v), 1)))))
            .collect(),
        frame_minus_empty_ms: all
            .into_iter()
            .map(|v| (v, median_of(log.frame_ms.get(&(Draw::Prop(v), 1))) - empty))
            .collect(),
        msaa_boxes,
        overdraw,
        depth_tested,
        covered,
        sphere_differ,
    }
}
