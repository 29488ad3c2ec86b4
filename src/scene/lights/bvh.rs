//! The light sampler of next-event estimation: a bounding volume hierarchy over the lights
//! that have a place (emitting primitives, point and spot lights), each node bounding its
//! lights' positions, power and emission directions, so that a point picks a light by an
//! estimate of what each part of the tree sends it (Conty Estevez and Kulla, "Importance
//! Sampling of Many Lights with Adaptive Tree Splitting", 2018; pbrt-v4's
//! `BVHLightSampler` is the model). Lights without a place — the environment and
//! directional lights — are picked with probability `n_infinite / (n_infinite + 1)`,
//! uniformly among them, as pbrt-v4 does. The pick's probability for any light at any
//! point is recomputed exactly ([`LightBvh::pmf`]) from the light's path down the tree, so
//! that multiple importance sampling weighs it right.
//!
//! A large dim emitter cannot starve small bright ones: it is bounded apart from them, and a
//! node's importance is its power over its squared distance, so the lamps near a point keep
//! their share whatever the dome's area.

use super::emission::Emitter;
use super::DeltaLight;
use crate::scene::Scene;
use glam::Vec3;
use std::f32::consts::PI;

/// What a node (or one light) holds: where, how much power, and in which directions.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightBounds {
    pub lo: Vec3,
    pub hi: Vec3,
    /// A measure of power: radiance × projected area, or intensity (what, over d², is the
    /// irradiance it sends).
    pub phi: f32,
    /// The cone of emitting normals: its axis and the cosine of its half-angle.
    pub w: Vec3,
    pub cos_o: f32,
    /// The cosine of the angle beyond the normals over which light leaves (π/2 for a
    /// Lambertian surface: 0).
    pub cos_e: f32,
    /// The largest radiance of a surface within (infinite for a point or spot light): no
    /// point receives more irradiance from the node than `π · radiance_max` times the
    /// share of its hemisphere that the bounds cover.
    pub radiance_max: f32,
}

fn safe_sqrt(x: f32) -> f32 {
    x.max(0.0).sqrt()
}

/// `sin²θb` of the cone of half-angle `θb` the bounds subtend (1 from inside them).
fn sin_b_cap(sin_b: f32, cos_b: f32) -> f32 {
    match cos_b <= 0.0 {
        true => 1.0,
        false => sin_b * sin_b,
    }
}

/// `cos(max(0, a − b))` from the angles' sines and cosines.
fn cos_sub_clamped(sin_a: f32, cos_a: f32, sin_b: f32, cos_b: f32) -> f32 {
    if cos_a > cos_b {
        1.0
    } else {
        cos_a * cos_b + sin_a * sin_b
    }
}

/// `sin(max(0, a − b))` from the angles' sines and cosines.
fn sin_sub_clamped(sin_a: f32, cos_a: f32, sin_b: f32, cos_b: f32) -> f32 {
    if cos_a > cos_b {
        0.0
    } else {
        sin_a * cos_b - cos_a * sin_b
    }
}

/// The smallest cone holding the cones `(wa, cos_a)` and `(wb, cos_b)` (pbrt-v4's
/// `DirectionCone::Union`).
fn cone_union(wa: Vec3, cos_a: f32, wb: Vec3, cos_b: f32) -> (Vec3, f32) {
    let (theta_a, theta_b) = (cos_a.clamp(-1.0, 1.0).acos(), cos_b.clamp(-1.0, 1.0).acos());
    let theta_d = wa.dot(wb).clamp(-1.0, 1.0).acos();
    if (theta_d + theta_b).min(PI) <= theta_a {
        return (wa, cos_a);
    }
    if (theta_d + theta_a).min(PI) <= theta_b {
        return (wb, cos_b);
    }
    let theta_o = 0.5 * (theta_a + theta_d + theta_b);
    if theta_o >= PI {
        return (wa, -1.0);
    }
    let theta_r = theta_o - theta_a;
    let axis = wa.cross(wb);
    if axis.length_squared() == 0.0 {
        return (wa, -1.0);
    }
    let k = axis.normalize();
    let (s, c) = theta_r.sin_cos();
    let w = (wa * c + k.cross(wa) * s).normalize();
    (w, theta_o.cos())
}

impl LightBounds {
    fn union(&self, other: &Self) -> Self {
        if self.phi == 0.0 {
            return *other;
        }
        if other.phi == 0.0 {
            return *self;
        }
        let (w, cos_o) = cone_union(self.w, self.cos_o, other.w, other.cos_o);
        Self {
            lo: self.lo.min(other.lo),
            hi: self.hi.max(other.hi),
            phi: self.phi + other.phi,
            w,
            cos_o,
            cos_e: self.cos_e.min(other.cos_e),
            radiance_max: self.radiance_max.max(other.radiance_max),
        }
    }

    fn centroid(&self) -> Vec3 {
        0.5 * (self.lo + self.hi)
    }

    /// An estimate of what the lights within send to point `p` with unit normal `n` (zero:
    /// a point that receives from both sides): `phi · cos θ' / d²`, `θ'` the smallest angle
    /// between `p` and the emitting normals the bounds allow, times the receiver's cosine
    /// bound; 0 only where no light within can reach `p`.
    pub fn importance(&self, p: Vec3, n: Vec3) -> f32 {
        if self.behind_every_emitter(p) {
            return 0.0;
        }
        let pc = self.centroid();
        let diag = self.hi - self.lo;
        let d2 = p
            .distance_squared(pc)
            .max(0.5 * diag.length())
            .max(f32::MIN_POSITIVE);
        let wi = (p - pc).normalize_or_zero();
        let cos_w = self.w.dot(wi);
        let sin_w = safe_sqrt(1.0 - cos_w * cos_w);
        // The cone of directions the bounds subtend at `p` (the whole sphere inside them).
        let r2 = 0.25 * diag.length_squared();
        let (sin_b, cos_b) = if p.distance_squared(pc) < r2 {
            (0.0, -1.0)
        } else {
            let sin2 = r2 / p.distance_squared(pc);
            (safe_sqrt(sin2), safe_sqrt(1.0 - sin2))
        };
        let sin_o = safe_sqrt(1.0 - self.cos_o * self.cos_o);
        let cos_x = cos_sub_clamped(sin_w, cos_w, sin_o, self.cos_o);
        let sin_x = sin_sub_clamped(sin_w, cos_w, sin_o, self.cos_o);
        let cos_p = cos_sub_clamped(sin_x, cos_x, sin_b, cos_b);
        if cos_p <= self.cos_e {
            return 0.0;
        }
        // Power over squared distance overstates what a large emitter sends to a point near
        // or inside it (a dome over the scene): no surface of radiance `L` seen in a cone of
        // half-angle `θb` gives more irradiance than `π · L · sin²θb`.
        let cap = PI * self.radiance_max * sin_b_cap(sin_b, cos_b);
        let mut importance = (self.phi * cos_p / d2).min(cap);
        if n != Vec3::ZERO {
            let cos_i = wi.dot(n).abs();
            let sin_i = safe_sqrt(1.0 - cos_i * cos_i);
            importance *= cos_sub_clamped(sin_i, cos_i, sin_b, cos_b);
        }
        // Finite, so that two children's sum is (in f64, [`LightBvh::sample`]).
        importance.clamp(0.0, f32::MAX)
    }

    /// Whether `p` lies behind (or in) the plane of every surface within, where all of them
    /// face one way and emit only in front (one emitting triangle or disk, or coplanar
    /// ones): then none sends it anything. The cone bound alone misses it near the bounds,
    /// where they subtend a wide cone (a point on the ceiling beside a ceiling lamp).
    fn behind_every_emitter(&self, p: Vec3) -> bool {
        if self.cos_o < 1.0 || self.cos_e > 0.0 {
            return false;
        }
        // The least `x · w` over the box: the plane through the box's rearmost corner.
        let least = (self.lo * self.w).min(self.hi * self.w).element_sum();
        p.dot(self.w) <= least
    }

    /// pbrt-v4's cost of a node for the build: power × the solid angle its normal and
    /// emission cones cover × the surface area of its box (stretched boxes cost more).
    fn cost(&self, axis: usize) -> f32 {
        let theta_o = self.cos_o.clamp(-1.0, 1.0).acos();
        let theta_e = self.cos_e.clamp(-1.0, 1.0).acos();
        let theta_w = (theta_o + theta_e).min(PI);
        let sin_o = safe_sqrt(1.0 - self.cos_o * self.cos_o);
        let m_omega = 2.0 * PI * (1.0 - self.cos_o)
            + PI / 2.0
                * (2.0 * theta_w * sin_o - (theta_o - 2.0 * theta_w).cos() - 2.0 * theta_o * sin_o
                    + self.cos_o);
        let d = self.hi - self.lo;
        let area = 2.0 * (d.x * d.y + d.y * d.z + d.z * d.x);
        let kr = d.max_element() / d[axis].max(f32::MIN_POSITIVE);
        self.phi * m_omega * kr * area.max(f32::MIN_POSITIVE)
    }
}

/// A light the tree holds: an emitting primitive, or a point or spot light.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Bounded {
    Area(u32),
    Delta(u32),
}

impl From<Bounded> for Emitter {
    fn from(b: Bounded) -> Self {
        match b {
            Bounded::Area(p) => Emitter::Area(p),
            Bounded::Delta(i) => Emitter::Delta(i),
        }
    }
}

#[derive(Clone, Copy, Debug)]
struct Node {
    bounds: LightBounds,
    /// A leaf's light (an index of [`LightBvh::lights`]), or an interior node's second
    /// child (its first is the next node).
    index: u32,
    leaf: bool,
}

/// The tree, and the lights outside it.
#[derive(Clone, Debug, Default)]
pub struct LightBvh {
    nodes: Vec<Node>,
    lights: Vec<Bounded>,
    /// Per light of `lights`, its way down from the root: bit `k` set where the `k`-th
    /// step goes to the second child.
    trails: Vec<u64>,
    /// Per emitting primitive (in [`crate::scene::Emitters::prims`]' order), and per delta
    /// light, its index in `lights` (`u32::MAX` for a directional light).
    area_index: Vec<u32>,
    delta_index: Vec<u32>,
    /// The environment and directional lights.
    infinite: Vec<Emitter>,
}

/// Deepest the tree goes (a trail is 64 bits); below it, splits are at the median.
const MAX_DEPTH: usize = 60;

impl LightBvh {
    /// The tree over `scene`'s lights.
    pub fn new(scene: &Scene) -> Self {
        let mut items: Vec<(LightBounds, Bounded)> = Vec::new();
        let mut area_index = Vec::with_capacity(scene.emitters.prims.len());
        for &prim in &scene.emitters.prims {
            area_index.push(u32::MAX);
            if let Some(b) = area_bounds(scene, prim) {
                *area_index.last_mut().unwrap() = items.len() as u32;
                items.push((b, Bounded::Area(prim)));
            }
        }
        let mut infinite: Vec<Emitter> = scene
            .environment
            .iter()
            .map(|_| Emitter::Environment)
            .collect();
        let mut delta_index = Vec::with_capacity(scene.delta_lights.len());
        for (i, light) in scene.delta_lights.iter().enumerate() {
            delta_index.push(u32::MAX);
            match delta_bounds(light) {
                Some(b) if b.phi > 0.0 => {
                    *delta_index.last_mut().unwrap() = items.len() as u32;
                    items.push((b, Bounded::Delta(i as u32)));
                }
                Some(_) => {}
                None => infinite.push(Emitter::Delta(i as u32)),
            }
        }
        let mut bvh = Self {
            nodes: Vec::with_capacity(2 * items.len()),
            lights: items.iter().map(|&(_, l)| l).collect(),
            trails: vec![0; items.len()],
            area_index,
            delta_index,
            infinite,
        };
        let mut order: Vec<u32> = (0..items.len() as u32).collect();
        if !order.is_empty() {
            let bounds: Vec<LightBounds> = items.iter().map(|&(b, _)| b).collect();
            bvh.build(&bounds, &mut order, 0, 0);
        }
        bvh
    }

    /// Builds the subtree of `order`'s lights at `depth`, their trails so far `trail`;
    /// returns its root's bounds.
    fn build(
        &mut self,
        bounds: &[LightBounds],
        order: &mut [u32],
        depth: usize,
        trail: u64,
    ) -> LightBounds {
        let at = self.nodes.len();
        if order.len() == 1 {
            let light = order[0];
            self.trails[light as usize] = trail;
            self.nodes.push(Node {
                bounds: bounds[light as usize],
                index: light,
                leaf: true,
            });
            return bounds[light as usize];
        }
        let mid = split(bounds, order, depth >= MAX_DEPTH);
        self.nodes.push(Node {
            bounds: bounds[order[0] as usize],
            index: 0,
            leaf: false,
        });
        let (first, second) = order.split_at_mut(mid);
        let a = self.build(bounds, first, depth + 1, trail);
        let second_at = self.nodes.len() as u32;
        let b = self.build(bounds, second, depth + 1, trail | (1u64 << depth));
        let union = a.union(&b);
        self.nodes[at] = Node {
            bounds: union,
            index: second_at,
            leaf: false,
        };
        union
    }

    /// The probability of picking an infinite light at all.
    fn p_infinite(&self) -> f64 {
        let n = self.infinite.len() as f64;
        let tree = f64::from(u8::from(!self.nodes.is_empty()));
        if n + tree == 0.0 {
            0.0
        } else {
            n / (n + tree)
        }
    }

    /// The light picked for next-event estimation at `p` (unit normal `n`, or zero) by a
    /// uniform `u` in [0, 1): the light, its probability and `u` rescaled within the
    /// choice; `None` without lights, or where no light of the tree can reach `p`.
    pub fn sample(&self, p: Vec3, n: Vec3, u: f64) -> Option<(Emitter, f64, f64)> {
        let p_inf = self.p_infinite();
        if u < p_inf {
            let k = self.infinite.len();
            let x = u / p_inf * k as f64;
            let i = (x as usize).min(k - 1);
            return Some((
                self.infinite[i],
                p_inf / k as f64,
                (x - i as f64).clamp(0.0, ONE_BELOW),
            ));
        }
        if self.nodes.is_empty() {
            return None;
        }
        let mut u = ((u - p_inf) / (1.0 - p_inf)).clamp(0.0, ONE_BELOW);
        let mut pmf = 1.0 - p_inf;
        let mut at = 0usize;
        loop {
            let node = &self.nodes[at];
            if node.leaf {
                let light = self.lights[node.index as usize];
                return (at > 0 || node.bounds.importance(p, n) > 0.0).then_some((
                    light.into(),
                    pmf,
                    u,
                ));
            }
            let children = [at + 1, node.index as usize];
            let [p0, p1] = child_shares(children.map(|c| self.nodes[c].bounds.importance(p, n)))?;
            if u < p0 {
                u = (u / p0).clamp(0.0, ONE_BELOW);
                pmf *= p0;
                at = children[0];
            } else {
                u = ((u - p0) / (1.0 - p0)).clamp(0.0, ONE_BELOW);
                pmf *= p1;
                at = children[1];
            }
        }
    }

    /// The probability with which [`Self::sample`] picks `emitter` at `p` (normal `n`).
    pub fn pmf(&self, scene: &Scene, p: Vec3, n: Vec3, emitter: Emitter) -> f64 {
        let index = match emitter {
            Emitter::Environment => None,
            Emitter::Delta(i) => Some(self.delta_index[i as usize]),
            Emitter::Area(prim) => match scene.emitters.prims.binary_search(&prim) {
                Ok(k) => Some(self.area_index[k]),
                Err(_) => return 0.0,
            },
        };
        let index = match index {
            None => return self.p_infinite() / self.infinite.len().max(1) as f64,
            Some(u32::MAX) => {
                let infinite = self.infinite.contains(&emitter);
                return match infinite {
                    true => self.p_infinite() / self.infinite.len() as f64,
                    false => 0.0,
                };
            }
            Some(i) => i as usize,
        };
        let mut trail = self.trails[index];
        let mut pmf = 1.0 - self.p_infinite();
        let mut at = 0usize;
        loop {
            let node = &self.nodes[at];
            if node.leaf {
                return match at > 0 || node.bounds.importance(p, n) > 0.0 {
                    true => pmf,
                    false => 0.0,
                };
            }
            let children = [at + 1, node.index as usize];
            let Some(shares) =
                child_shares(children.map(|c| self.nodes[c].bounds.importance(p, n)))
            else {
                return 0.0;
            };
            let second = trail & 1 == 1;
            pmf *= shares[usize::from(second)];
            at = children[usize::from(second)];
            trail >>= 1;
        }
    }

    /// How many lights the tree holds.
    pub fn len(&self) -> usize {
        self.lights.len()
    }

    pub fn is_empty(&self) -> bool {
        self.lights.is_empty()
    }
}

/// The probabilities of descending into each of two children of importances `ci`; `None`
/// where neither can reach the point.
fn child_shares(ci: [f32; 2]) -> Option<[f64; 2]> {
    let total = f64::from(ci[0]) + f64::from(ci[1]);
    (total > 0.0).then(|| ci.map(|c| f64::from(c) / total))
}

/// The largest `f64` below 1.
const ONE_BELOW: f64 = 1.0 - f64::EPSILON / 2.0;

/// Sorts `order` into two groups and returns where the second starts: the bucket split of
/// least cost along the axis of the widest spread of centroids, or the median (`median`,
/// or where no bucket split separates anything).
fn split(bounds: &[LightBounds], order: &mut [u32], median: bool) -> usize {
    let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
    for &i in order.iter() {
        let c = bounds[i as usize].centroid();
        lo = lo.min(c);
        hi = hi.max(c);
    }
    let extent = hi - lo;
    let axis = if extent.x >= extent.y && extent.x >= extent.z {
        0
    } else if extent.y >= extent.z {
        1
    } else {
        2
    };
    let key = |i: &u32| bounds[*i as usize].centroid()[axis];
    let at_median = |order: &mut [u32]| {
        let mid = order.len() / 2;
        order.select_nth_unstable_by(mid, |a, b| key(a).total_cmp(&key(b)));
        mid
    };
    if median || extent[axis].is_nan() || extent[axis] <= 0.0 {
        return at_median(order);
    }
    const BUCKETS: usize = 12;
    let bucket_of = |i: &u32| {
        let t = (key(i) - lo[axis]) / extent[axis];
        ((t * BUCKETS as f32) as usize).min(BUCKETS - 1)
    };
    let mut buckets: [Option<LightBounds>; BUCKETS] = [None; BUCKETS];
    for i in order.iter() {
        let b = &mut buckets[bucket_of(i)];
        let light = bounds[*i as usize];
        *b = Some(b.map_or(light, |x| x.union(&light)));
    }
    let union = |range: &[Option<LightBounds>]| {
        range
            .iter()
            .flatten()
            .fold(None, |acc: Option<LightBounds>, b| {
                Some(acc.map_or(*b, |a| a.union(b)))
            })
    };
    let best = (1..BUCKETS)
        .filter_map(|s| {
            let (a, b) = (union(&buckets[..s])?, union(&buckets[s..])?);
            Some((s, a.cost(axis) + b.cost(axis)))
        })
        .min_by(|a, b| a.1.total_cmp(&b.1));
    let Some((s, bucket_cost)) = best else {
        return at_median(order);
    };
    if let Some(mid) = split_by_size(bounds, order, axis, bucket_cost) {
        return mid;
    }
    let mut mid = 0;
    for k in 0..order.len() {
        if bucket_of(&order[k]) < s {
            order.swap(k, mid);
            mid += 1;
        }
    }
    match mid == 0 || mid == order.len() {
        true => at_median(order),
        false => mid,
    }
}

/// The split that sets the largest lights apart from the rest, where it costs less than
/// `than` (the best split by position): a light whose bounds hold the others (a dome over
/// the scene) has its centroid among theirs, so no split by position can set it apart, and
/// the small lights grouped with it would share its importance. Sorts `order` largest
/// first and returns where the rest starts.
fn split_by_size(
    bounds: &[LightBounds],
    order: &mut [u32],
    axis: usize,
    than: f32,
) -> Option<usize> {
    let size = |i: &u32| {
        let b = &bounds[*i as usize];
        (b.hi - b.lo).length()
    };
    let mut sorted = order.to_vec();
    sorted.sort_by(|a, b| size(b).total_cmp(&size(a)).then(a.cmp(b)));
    let n = sorted.len();
    let mut suffix = vec![bounds[sorted[n - 1] as usize]; n];
    for k in (0..n - 1).rev() {
        suffix[k] = bounds[sorted[k] as usize].union(&suffix[k + 1]);
    }
    let mut prefix = bounds[sorted[0] as usize];
    let mut best: Option<(usize, f32)> = None;
    for k in 1..n {
        let cost = prefix.cost(axis) + suffix[k].cost(axis);
        if cost < than && best.is_none_or(|(_, c)| cost < c) {
            best = Some((k, cost));
        }
        prefix = prefix.union(&bounds[sorted[k] as usize]);
    }
    let (k, _) = best?;
    order.copy_from_slice(&sorted);
    Some(k)
}

/// The bounds of emitting primitive `prim` (one-sided: it emits on its normal's side);
/// `None` where it emits nothing.
fn area_bounds(scene: &Scene, prim: u32) -> Option<LightBounds> {
    let ke = scene.material(prim).ke;
    let radiance = (ke.x + ke.y + ke.z) / 3.0;
    let area = scene.mesh.area(prim) as f32;
    if !(radiance > 0.0 && area > 0.0) {
        return None;
    }
    let (lo, hi, w, cos_o, projected) = match scene.mesh.analytic(prim) {
        Some(shape) => {
            let (lo, hi) = shape.bounds();
            match shape {
                // Normals every way; seen from afar, a quarter of its area faces a point.
                crate::accel::Analytic::Sphere { .. } => {
                    (lo.as_vec3(), hi.as_vec3(), Vec3::Z, -1.0, 0.25 * area)
                }
                crate::accel::Analytic::Disk { normal, .. } => {
                    (lo.as_vec3(), hi.as_vec3(), normal.as_vec3(), 1.0, area)
                }
            }
        }
        None => {
            let [a, b, c] = scene.mesh.vertices(prim);
            (
                a.min(b).min(c),
                a.max(b).max(c),
                scene.mesh.normals[prim as usize],
                1.0,
                area,
            )
        }
    };
    Some(LightBounds {
        lo,
        hi,
        phi: radiance * projected,
        w,
        cos_o,
        cos_e: 0.0,
        radiance_max: radiance,
    })
}

/// The bounds of a point or spot light; `None` for a directional light (it has no place).
fn delta_bounds(light: &DeltaLight) -> Option<LightBounds> {
    let mean = |v: Vec3| (v.x + v.y + v.z) / 3.0;
    match *light {
        DeltaLight::Point {
            position,
            intensity,
        } => Some(LightBounds {
            lo: position,
            hi: position,
            phi: mean(intensity),
            w: Vec3::Z,
            cos_o: -1.0,
            cos_e: 0.0,
            radiance_max: f32::INFINITY,
        }),
        DeltaLight::Spot(s) => Some(LightBounds {
            lo: s.position,
            hi: s.position,
            phi: mean(s.intensity),
            w: s.axis,
            cos_o: s.cos_beam,
            cos_e: (s.cutoff_angle - s.beam_width).cos(),
            radiance_max: f32::INFINITY,
        }),
        DeltaLight::Directional { .. } => None,
    }
}
