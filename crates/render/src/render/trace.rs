//! Ray–surface intersection by Lipschitz tracing.
//!
//! Both methods march along a ray clipped to the field's support box and only ever take
//! steps that cannot skip the surface `f = T`: on a stretch of the ray where the field is
//! λ-Lipschitz, `|f(t) − T| / λ` is a lower bound of the distance to the surface.
//!
//! * [`Method::Sphere`] is plain sphere tracing (Hart 1996; Génevaux et al. 2015 §7.1) with the
//!   field's **global** Lipschitz bound.
//! * [`Method::Segment`] is the accelerated tracing of Génevaux et al. 2015 §7.2, the same idea as
//!   segment tracing (Galin et al. 2020): at `t`, take a candidate segment `[t, t + δ]`,
//!   ask the field for its Lipschitz bound λ on that segment only, and step by
//!   `s = |f(t) − T| / λ`. When `s ≥ δ` the whole candidate is safe: step `δ` and double
//!   it; otherwise retry with `δ/4` (the value at `t` is kept, only the bound is asked
//!   again) while that stays above `s`, then step `s` and shrink `δ` to `s`. Local bounds
//!   of compactly supported primitives are far smaller than the global one, so steps are
//!   much longer.
//!
//! Steps are never shorter than the tolerance `ε + cone·t` (metres; the cone term is the
//! pixel footprint): near the surface the march steps across it, and the crossing is
//! located by false position (Illinois) to a tenth of the tolerance. Rays that start inside the solid
//! find where they leave it.

use std::sync::Arc;

use glam::Vec3;

use super::camera::Ray;
use super::guide::Guide;
use crate::field::{Field, ISO, Line, Tree};

/// Which step rule to use.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Method {
    /// Local Lipschitz bounds over candidate segments (Génevaux et al. 2015 §7.2).
    #[default]
    Segment,
    /// Plain sphere tracing with the global Lipschitz bound.
    Sphere,
}

impl Method {
    /// Each method with the name the command line gives it.
    pub const NAMES: [(&'static str, Method); 2] =
        [("segment", Method::Segment), ("sphere", Method::Sphere)];
}

impl std::str::FromStr for Method {
    type Err = String;

    fn from_str(s: &str) -> Result<Method, String> {
        Method::NAMES
            .iter()
            .find(|(n, _)| n.eq_ignore_ascii_case(s))
            .map(|&(_, m)| m)
            .ok_or_else(|| format!("unknown method {s:?} (expected segment or sphere)"))
    }
}

/// Tracing tolerances and limits.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TraceParams {
    /// The step rule.
    pub method: Method,
    /// Surface tolerance at the ray origin, metres.
    pub epsilon: f32,
    /// Growth of the tolerance per metre along the ray (half a pixel's angle for primary
    /// rays, so far surfaces stop at the pixel's footprint).
    pub cone: f32,
    /// Field evaluations allowed per ray before it is declared a miss.
    pub max_steps: u32,
    /// Factor by which a fully safe candidate segment grows (segment tracing).
    pub grow: f32,
}

impl TraceParams {
    /// Tolerances scaled to a scene of the given size (the support box's diagonal):
    /// `ε = size · 1e-4`, no cone, generous step limits.
    pub fn for_scene(method: Method, size: f32) -> Self {
        TraceParams {
            method,
            epsilon: size.max(1e-6) * 1e-4,
            cone: 0.0,
            max_steps: match method {
                Method::Segment => 2_000,
                Method::Sphere => 200_000,
            },
            grow: 2.0,
        }
    }

    /// The same parameters with the pixel cone set for `pixel_angle` radians per pixel.
    pub fn with_pixel_angle(self, pixel_angle: f32) -> Self {
        TraceParams {
            cone: 0.5 * pixel_angle,
            ..self
        }
    }
}

/// The result of tracing one ray.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Trace {
    /// Ray parameter of the hit (metres from the origin); `f32::INFINITY` on a miss.
    pub t: f32,
    /// Field evaluations spent (marching plus refinement).
    pub steps: u32,
}

impl Trace {
    /// True when the ray hit the surface.
    pub fn hit(&self) -> bool {
        self.t.is_finite()
    }

    fn with_steps(self, steps: u32) -> Trace {
        Trace { steps, ..self }
    }
}

/// Most evaluations used to locate a bracketed crossing.
const MAX_REFINE: u32 = 12;

/// When a candidate segment is not safe, it is retried this many times shorter (its
/// local bound is then smaller) before the march settles for the safe step: the value at
/// `t` is reused, only the bound is asked again.
const SHRINK: f32 = 0.25;

/// How far from a mesh face, in cells of its mesh, the surface is sought first
/// ([`bracket`]): a Marching Cubes face lies far closer to the surface than a cell, and
/// from a quarter of a cell false position has less to do than from a cell (the main
/// job's view: 5.2 evaluations a ray, from 5.7).
const BRACKET_NEAR: f32 = 0.25;

/// First candidate segment, as a fraction of the clipped span.
const FIRST_DELTA: f32 = 1.0 / 16.0;

/// Traces `ray` over `t ∈ [t0, t1]` (normally the ray clipped to the support box) and
/// returns the first crossing of the surface.
///
/// Steps never fall below the tolerance `ε + cone·t`, so once the safe distance gets that
/// small the march steps over the surface and the crossing is bracketed; false position then
/// locates it to a tenth of the tolerance. Stopping on a small safe step alone
/// (classic sphere tracing) would stop short wherever the Lipschitz bound is loose —
/// with a blend's global bound, everywhere.
///
/// For many rays, a [`Tracer`] per thread is faster on trees with large blends.
pub fn trace(field: &dyn Field, ray: &Ray, span: (f32, f32), params: &TraceParams) -> Trace {
    Tracer::new(field).trace(ray, span, params)
}

/// True when the ray meets the surface on `[t0, t1]`: a shadow query. Same march as
/// [`trace`], but it stops at the first bracketed crossing without locating it.
pub fn occluded(field: &dyn Field, ray: &Ray, span: (f32, f32), params: &TraceParams) -> bool {
    Tracer::new(field).occluded(ray, span, params)
}

/// Traces rays through one field. When the field is a [`Tree`] with BVH blends, each ray
/// is a [`Line`]: it lists the blends' children it crosses as it goes, and the march's
/// values and segment bounds scan those short lists instead of descending the BVHs at every
/// step. The answers are the same. Keep one per thread: the line's buffers are reused.
pub struct Tracer<'f> {
    field: &'f dyn Field,
    /// The field as a tree, when it has blends with BVHs.
    line: Option<Line<'f>>,
    /// Meshed regions, finest first, where the march follows their meshes ([`Guide`]).
    guides: &'f [Arc<Guide>],
}

impl<'f> Tracer<'f> {
    /// A tracer for `field`.
    pub fn new(field: &'f dyn Field) -> Self {
        let line = field
            .as_any()
            .and_then(|a| a.downcast_ref::<Tree>())
            .filter(|t| t.keeps_line_lists())
            .map(Line::new);
        Tracer {
            field,
            line,
            guides: &[],
        }
    }

    /// The same tracer following, inside each guide's grid, that guide's mesh
    /// ([`Guide`]); where grids overlap, the first one's. Finest first.
    pub fn with_guides(self, guides: &'f [Arc<Guide>]) -> Self {
        Tracer { guides, ..self }
    }

    /// [`trace`] with this tracer.
    pub fn trace(&mut self, ray: &Ray, span: (f32, f32), params: &TraceParams) -> Trace {
        self.march(ray, span, params, true)
    }

    /// The gradient of the field at `ray.at(t)`, for a hit `t` that [`Tracer::trace`]
    /// just found along `ray`: through the line's lists when the tracer keeps them and is
    /// still on that ray, else from the field. [`outward`] makes it the normal.
    pub fn gradient(&mut self, ray: &Ray, t: f32) -> Vec3 {
        match &mut self.line {
            Some(line) if line.runs_along(ray.origin, ray.dir) => line.value_grad(t).1,
            _ => self.field.value_grad(ray.at(t)).1,
        }
    }

    /// [`occluded`] with this tracer.
    pub fn occluded(&mut self, ray: &Ray, span: (f32, f32), params: &TraceParams) -> bool {
        self.march(ray, span, params, false).hit()
    }

    /// The march over `span`, guided inside `guide`'s grid ([`Guide`]): the part of the
    /// span before the grid, the grid's marked runs (those a cell or more before the
    /// first face are skipped; around the face a bracket of the surface is tried first),
    /// then the part after, until one of them hits.
    fn march(&mut self, ray: &Ray, span: (f32, f32), params: &TraceParams, locate: bool) -> Trace {
        self.march_guided(0, ray, span, params, locate)
    }

    /// [`Self::march`] with the guides from `level` on: the part of the span inside
    /// guide `level`'s grid follows it, the parts outside go to the next guides.
    fn march_guided(
        &mut self,
        level: usize,
        ray: &Ray,
        span: (f32, f32),
        params: &TraceParams,
        locate: bool,
    ) -> Trace {
        let grid = self
            .guides
            .get(level)
            .map(|g| &**g)
            .and_then(|g| ray.clip(&g.bounds()).map(|c| (g, c)))
            .map(|(g, (a, b))| (g, (a.max(span.0), b.min(span.1))))
            .filter(|(_, (a, b))| a <= b);
        let Some((guide, (a, b))) = grid else {
            return match level < self.guides.len() {
                true => self.march_guided(level + 1, ray, span, params, locate),
                false => self.march_span(ray, span, params, locate),
            };
        };
        let mut steps = 0;
        if span.0 < a {
            let before = self.march_guided(level + 1, ray, (span.0, a), params, locate);
            steps += before.steps;
            if before.hit() {
                return before.with_steps(steps);
            }
        }
        let h = guide.cell();
        if !locate {
            // A shadow query, answered by the mesh alone (`Guide::hides`): a face through
            // which the ray enters the mesh's solid occludes, and so does being inside
            // it two cells of the finest guide on (at most a cell of this one). Faces it
            // leaves through before that do not: they are those of the surface it
            // leaves, which the mesh follows to within a cell, above or below the
            // field's.
            if guide.hides(ray, (a, b), h.min(2.0 * self.guides[0].cell())) {
                return Trace { t: b, steps };
            }
            if b < span.1 {
                let after = self.march_guided(level + 1, ray, (b, span.1), params, false);
                return after.with_steps(steps + after.steps);
            }
            return Trace {
                t: f32::INFINITY,
                steps,
            };
        }
        // The first face at or after the current run, once asked.
        let mut face: Option<Option<f32>> = None;
        for run in guide.runs(ray, (a, b)) {
            if face.is_none_or(|f| f.is_some_and(|t| t < run.0)) {
                face = Some(guide.first_face(ray, (run.0, b)));
            }
            let skip = face.flatten().is_none_or(|t| run.1 < t - h);
            if skip {
                // The mesher saw no surface in this run: the ray is in the air at its
                // end, unless it slipped between two faces into the solid.
                steps += 1;
                if OnRay(self.field, ray).value(run.1) <= ISO {
                    continue;
                }
            }
            let from = match face.flatten().filter(|_| !skip) {
                Some(t) => {
                    let span = (run.0.max(t - h), run.1.min(t + h));
                    let tol = params.epsilon + params.cone * span.0;
                    // The line's lists must cover the bracket: the hit's gradient is
                    // taken through them.
                    let found = match &mut self.line {
                        Some(line) => {
                            line.restrict(ray.origin, ray.dir, span);
                            bracket(line, t, span, BRACKET_NEAR * h, 0.1 * tol)
                        }
                        None => bracket(
                            &mut OnRay(self.field, ray),
                            t,
                            span,
                            BRACKET_NEAR * h,
                            0.1 * tol,
                        ),
                    };
                    let (from, n) = match found {
                        Bracket::Hit(tr) => return tr.with_steps(steps + tr.steps),
                        Bracket::Air(n) => (span.0, n),
                        // In the solid already: the surface came earlier in the run.
                        Bracket::Solid(n) => (run.0, n),
                    };
                    steps += n;
                    from
                }
                None => run.0,
            };
            let tr = self.march_span(ray, (from, run.1), params, locate);
            steps += tr.steps;
            if tr.hit() {
                return tr.with_steps(steps);
            }
        }
        if b < span.1 {
            let after = self.march_guided(level + 1, ray, (b, span.1), params, locate);
            return after.with_steps(steps + after.steps);
        }
        Trace {
            t: f32::INFINITY,
            steps,
        }
    }

    fn march_span(
        &mut self,
        ray: &Ray,
        span: (f32, f32),
        params: &TraceParams,
        locate: bool,
    ) -> Trace {
        let global = match params.method {
            Method::Sphere => self.field.lipschitz(),
            Method::Segment => 0.0,
        };
        match &mut self.line {
            Some(line) => {
                line.restrict(ray.origin, ray.dir, span);
                march(line, global, span, params, locate)
            }
            None => march(&mut OnRay(self.field, ray), global, span, params, locate),
        }
    }
}

/// The field seen along one ray, as the march asks it.
trait Along {
    /// `f` at parameter `t`.
    fn value(&mut self, t: f32) -> f32;
    /// A Lipschitz bound on `[t0, t1]`.
    fn lipschitz(&mut self, t0: f32, t1: f32) -> f32;
}

/// Any field, evaluated at the ray's points.
struct OnRay<'a>(&'a dyn Field, &'a Ray);

impl Along for OnRay<'_> {
    fn value(&mut self, t: f32) -> f32 {
        self.0.value(self.1.at(t))
    }
    fn lipschitz(&mut self, t0: f32, t1: f32) -> f32 {
        self.0.lipschitz_segment(self.1.at(t0), self.1.at(t1))
    }
}

/// A tree restricted to the ray.
impl Along for Line<'_> {
    fn value(&mut self, t: f32) -> f32 {
        Line::value(self, t)
    }
    fn lipschitz(&mut self, t0: f32, t1: f32) -> f32 {
        Line::lipschitz(self, t0, t1)
    }
}

/// The march of [`trace`]; `locate` refines a bracketed crossing (else `t` is the end of
/// the bracket).
fn march(
    along: &mut impl Along,
    global: f32,
    (t0, t1): (f32, f32),
    params: &TraceParams,
    locate: bool,
) -> Trace {
    let miss = |steps| Trace {
        t: f32::INFINITY,
        steps,
    };
    if t0.is_nan() || t1.is_nan() || t0 > t1 {
        return miss(0);
    }
    let mut t = t0;
    // A first candidate of a sixteenth of the span: long enough to cross empty space in a
    // few doublings, short enough that its bound is local.
    let mut delta = (t1 - t0) * FIRST_DELTA;
    let mut steps = 0;
    let mut side = 0.0f32;
    let (mut prev_t, mut prev_e) = (t0, 0.0);
    while steps < params.max_steps {
        let e = along.value(t) - ISO;
        steps += 1;
        let s_now = if e > 0.0 { 1.0 } else { -1.0 };
        if side == 0.0 {
            side = s_now;
        } else if s_now != side {
            if !locate {
                return Trace { t, steps };
            }
            let tol = params.epsilon + params.cone * prev_t;
            let (t_hit, n) = refine(along, (prev_t, prev_e), (t, e), 0.1 * tol);
            return Trace {
                t: t_hit,
                steps: steps + n,
            };
        }
        if t >= t1 {
            break;
        }
        let tol = params.epsilon + params.cone * t;
        let (step, next_delta) = match params.method {
            Method::Sphere => (safe_step(e, global), delta),
            Method::Segment => {
                let mut len = (t + delta).min(t1) - t;
                loop {
                    let s = safe_step(e, along.lipschitz(t, t + len));
                    if s >= len {
                        break (len, len * params.grow);
                    }
                    if len * SHRINK <= s.max(tol) {
                        break (s, s.max(tol));
                    }
                    len *= SHRINK;
                }
            }
        };
        (prev_t, prev_e) = (t, e);
        t = (t + step.max(tol)).min(t1);
        delta = next_delta;
    }
    miss(steps)
}

/// What [`bracket`] found.
enum Bracket {
    /// The surface, located (its evaluations counted).
    Hit(Trace),
    /// No crossing found, the span's start in the air (evaluations spent).
    Air(u32),
    /// The span's start in the solid (evaluations spent).
    Solid(u32),
}

/// Tries to bracket the surface around `t`, a mesh face's parameter, within `span`. The
/// span's start must be in the air (else the surface came earlier: [`Bracket::Solid`]);
/// then the field at the face tells on which side of it the surface lies, and there it
/// is sought `near` away first (a mesh's faces lie far closer to the surface than a
/// cell: a short bracket leaves false position less to do), then at the span's end. A
/// bracket found is located by false position to `width`.
fn bracket(along: &mut impl Along, t: f32, (s0, s1): (f32, f32), near: f32, width: f32) -> Bracket {
    let e0 = along.value(s0) - ISO;
    if e0 > 0.0 {
        return Bracket::Solid(1);
    }
    let t = t.clamp(s0, s1);
    let e = along.value(t) - ISO;
    let mut steps = 2;
    // Solid at the face: the surface lies between the start and the face, `near` before
    // it first. Air: after it, `near` after it first, else by the span's end.
    let (mut last, tries) = match e > 0.0 {
        true => ((s0, e0), [t - near, t]),
        false => ((t, e), [t + near, s1]),
    };
    for s in tries {
        let s = s.clamp(s0, s1);
        if s <= last.0 {
            continue;
        }
        let es = match s == t {
            true => e,
            false => {
                steps += 1;
                along.value(s) - ISO
            }
        };
        if es > 0.0 {
            let (t, n) = refine(along, last, (s, es), width);
            return Bracket::Hit(Trace {
                t,
                steps: steps + n,
            });
        }
        last = (s, es);
    }
    Bracket::Air(steps)
}

/// `|e| / λ`, infinite where the field is flat.
#[inline]
fn safe_step(e: f32, lambda: f32) -> f32 {
    if lambda > 0.0 {
        e.abs() / lambda
    } else {
        f32::INFINITY
    }
}

/// Locates the crossing of `T` between `a` and `b` (field offsets `e = f − T` of opposite
/// signs) by false position with the Illinois modification, until the bracket or the
/// next move is below `width` (the point that move reaches is returned without being
/// evaluated: it lies within `width` of the last point evaluated, and its value would
/// only confirm it); returns `t` and the evaluations spent.
fn refine(
    along: &mut impl Along,
    (mut a, mut ea): (f32, f32),
    (mut b, mut eb): (f32, f32),
    width: f32,
) -> (f32, u32) {
    let mut n = 0;
    let mut last = f32::NAN;
    let mut m = 0.5 * (a + b);
    let mut kept = 0i8; // which end was kept last: -1 a, 1 b

    while n < MAX_REFINE && b - a > width {
        m = if ea != eb {
            a + (b - a) * ea / (ea - eb)
        } else {
            0.5 * (a + b)
        };
        m = m.clamp(a, b);
        if (m - last).abs() < width {
            break;
        }
        let e = along.value(m) - ISO;
        n += 1;
        last = m;
        // Illinois: when the same end is kept twice in a row, halve its weight.
        if (e > 0.0) == (ea > 0.0) {
            (a, ea) = (m, e);
            if kept == 1 {
                eb *= 0.5;
            }
            kept = 1;
        } else {
            (b, eb) = (m, e);
            if kept == -1 {
                ea *= 0.5;
            }
            kept = -1;
        }
    }
    (m, n)
}

/// The outward unit normal at `p`: `−∇f / |∇f|` (solid where `f > T`); `+Z` where the
/// gradient vanishes.
pub fn normal(field: &dyn Field, p: Vec3) -> Vec3 {
    outward(field.value_grad(p).1)
}

/// The outward unit normal `−g / |g|` of a gradient `g`, or `+Z` where it vanishes or is
/// not finite.
pub fn outward(g: Vec3) -> Vec3 {
    let n = -g;
    let l = n.length();
    if l > 0.0 && l.is_finite() {
        n / l
    } else {
        Vec3::Z
    }
}
