//! A bounding-volume hierarchy over a mesh's triangles for closest-point and radius queries:
//! median splits of the centroids along the longest axis down to leaves of up to four
//! triangles, then collapsed to four children per node (their boxes side by side, so that one
//! visit measures all four: half the visits of the binary tree, in a loop the compiler
//! vectorises).

use super::triangle::{closer, closest_on_triangle, may_be_within, Closest, Triangle};
use crate::ordered::more;
use glam::DVec3;

/// Triangles per leaf.
const LEAF_SIZE: usize = 4;
/// Children per node.
const WIDTH: usize = 4;
/// Entries of a query's stack: a visit pushes at most `WIDTH` and pops one, so a hierarchy of
/// depth `k` needs at most `(WIDTH − 1) k + 1`; median splits give depth `log₄(n / 4) + 1`
/// (13 for 2²⁶ triangles).
const STACK: usize = 64;

/// Four children: their boxes by axis, and what each is.
#[derive(Clone, Copy, Debug)]
struct Node {
    lo: [[f64; WIDTH]; 3],
    hi: [[f64; WIDTH]; 3],
    /// An inner child's node index, or a leaf's first triangle.
    first: [u32; WIDTH],
    /// A leaf's triangle count; 0 for an inner child, and for an empty slot (whose box is
    /// empty: `lo = +∞`, `hi = −∞`, never within any distance).
    count: [u32; WIDTH],
}

impl Node {
    const EMPTY: Node = Node { lo: [[f64::INFINITY; WIDTH]; 3], hi: [[f64::NEG_INFINITY; WIDTH]; 3], first: [0; WIDTH], count: [0; WIDTH] };

    /// The squared distances from `p` to the four boxes (`+∞` for empty slots). Maxima by
    /// comparison (`ordered`): the queries' points are finite (a mesh build's 4.3 % of
    /// instructions were `f64::max`'s NaN handling here).
    #[inline]
    fn distances_sq(&self, p: DVec3) -> [f64; WIDTH] {
        let mut d = [0.0; WIDTH];
        for (axis, c) in [p.x, p.y, p.z].into_iter().enumerate() {
            for (k, dk) in d.iter_mut().enumerate() {
                let t = more(more(self.lo[axis][k] - c, c - self.hi[axis][k]), 0.0);
                *dk += t * t;
            }
        }
        d
    }

    fn is_leaf(&self, k: usize) -> bool {
        self.count[k] > 0
    }
}

/// A node of the binary tree the hierarchy is built from.
#[derive(Clone, Copy, Debug)]
struct Binary {
    min: DVec3,
    max: DVec3,
    /// Inner: the left child (the right one follows it). Leaf: the first triangle.
    first: u32,
    /// Triangles of a leaf; 0 for an inner node.
    count: u32,
}

#[derive(Clone, Debug)]
pub(super) struct Bvh {
    nodes: Vec<Node>,
    bounds: (DVec3, DVec3),
}

impl Bvh {
    /// Builds the hierarchy over `triangles`; with it, their leaf order (the hierarchy's leaves
    /// refer to the triangles in that order).
    pub fn build(triangles: &[Triangle]) -> (Bvh, Vec<u32>) {
        let mut order: Vec<u32> = (0..triangles.len() as u32).collect();
        let mut binary = vec![Binary { min: DVec3::ZERO, max: DVec3::ZERO, first: 0, count: 0 }];
        fill(&mut binary, triangles, &mut order, 0, 0, triangles.len());
        let mut nodes = vec![Node::EMPTY];
        collapse(&binary, 0, &mut nodes, 0);
        (Bvh { nodes, bounds: (binary[0].min, binary[0].max) }, order)
    }

    /// The bounds of every triangle.
    pub fn bounds(&self) -> (DVec3, DVec3) {
        self.bounds
    }

    /// The closest point of the whole mesh to `p`, starting from `best` (a triangle's closest
    /// point near the answer prunes most of the hierarchy; [`Closest::NONE`] for none).
    pub fn closest(&self, triangles: &[Triangle], p: DVec3, mut best: Closest) -> Closest {
        // Children to visit with their box distances, the nearest on top.
        let mut stack = [(0u32, 0u32, 0f64); STACK];
        let mut top = 0;
        let mut node = 0usize;
        loop {
            let n = &self.nodes[node];
            let d = n.distances_sq(p);
            // The children within reach (`>`, not `>=`: a triangle at the same distance with a
            // smaller index wins ties; never an empty slot, nor a box at an infinite or NaN
            // distance), pushed farthest first by insertion.
            let base = top;
            for (k, &dk) in d.iter().enumerate() {
                if !(dk <= best.distance_sq && dk < f64::INFINITY) {
                    continue;
                }
                let mut at = top;
                while at > base && stack[at - 1].2 < dk {
                    stack[at] = stack[at - 1];
                    at -= 1;
                }
                stack[at] = (n.first[k], n.count[k], dk);
                top += 1;
            }
            // The next inner node; leaves on the way are searched at once.
            loop {
                if top == 0 {
                    return best;
                }
                top -= 1;
                let (first, count, distance_sq) = stack[top];
                if distance_sq > best.distance_sq {
                    continue;
                }
                if count == 0 {
                    node = first as usize;
                    break;
                }
                for i in first..first + count {
                    if !may_be_within(&triangles[i as usize], p, best.distance_sq) {
                        continue;
                    }
                    let c = closest_on_triangle(&triangles[i as usize], p, i);
                    if closer(&c, &best) {
                        best = c;
                    }
                }
            }
        }
    }

    /// Every triangle within distance `radius` of `p`, in the triangles' order, or `false` (and
    /// a partial list) as soon as there are more than `max`.
    pub fn within(&self, triangles: &[Triangle], p: DVec3, radius: f64, max: usize, out: &mut Vec<u32>) -> bool {
        out.clear();
        let complete = self.visit_within(triangles, p, radius, |i, _| {
            out.push(i);
            out.len() <= max
        });
        if complete {
            out.sort_unstable();
        }
        complete
    }

    /// [`Self::within`] with each triangle's squared distance (`(distance², index)`, in no
    /// particular order).
    pub fn within_distances(&self, triangles: &[Triangle], p: DVec3, radius: f64, max: usize, out: &mut Vec<(f64, u32)>) -> bool {
        out.clear();
        self.visit_within(triangles, p, radius, |i, distance_sq| {
            out.push((distance_sq, i));
            out.len() <= max
        })
    }

    /// Calls `found(index, distance²)` for every triangle within `radius` of `p` (its closest
    /// point's distance), until `found` returns `false`; whether it never did.
    fn visit_within(&self, triangles: &[Triangle], p: DVec3, radius: f64, mut found: impl FnMut(u32, f64) -> bool) -> bool {
        let r2 = radius * radius;
        let mut stack = [0u32; STACK];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let n = &self.nodes[stack[top] as usize];
            let d = n.distances_sq(p);
            for (k, &dk) in d.iter().enumerate() {
                if !(dk <= r2 && dk < f64::INFINITY) {
                    continue;
                }
                if n.is_leaf(k) {
                    for i in n.first[k]..n.first[k] + n.count[k] {
                        // (The cheap test first: it fails only farther than `radius`.)
                        if !may_be_within(&triangles[i as usize], p, r2) {
                            continue;
                        }
                        let distance_sq = closest_on_triangle(&triangles[i as usize], p, i).distance_sq;
                        if distance_sq <= r2 && !found(i, distance_sq) {
                            return false;
                        }
                    }
                } else {
                    stack[top] = n.first[k];
                    top += 1;
                }
            }
        }
        true
    }
}

/// Fills binary node `slot` with the hierarchy over `order[first..first + count]`.
fn fill(nodes: &mut Vec<Binary>, triangles: &[Triangle], order: &mut [u32], slot: usize, first: usize, count: usize) {
    let (mut min, mut max) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    let (mut cmin, mut cmax) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    for &i in &order[first..first + count] {
        for v in triangles[i as usize].p {
            min = min.min(v);
            max = max.max(v);
        }
        cmin = cmin.min(triangles[i as usize].centre);
        cmax = cmax.max(triangles[i as usize].centre);
    }
    if count <= LEAF_SIZE {
        nodes[slot] = Binary { min, max, first: first as u32, count: count as u32 };
        return;
    }
    let extent = cmax - cmin;
    let axis = if extent.x >= extent.y && extent.x >= extent.z { 0 } else if extent.y >= extent.z { 1 } else { 2 };
    let half = count / 2;
    order[first..first + count].select_nth_unstable_by(half, |&a, &b| triangles[a as usize].centre[axis].total_cmp(&triangles[b as usize].centre[axis]));
    let left = nodes.len();
    nodes.extend([Binary { min, max, first: 0, count: 0 }; 2]);
    nodes[slot] = Binary { min, max, first: left as u32, count: 0 };
    fill(nodes, triangles, order, left, first, half);
    fill(nodes, triangles, order, left + 1, first + half, count - half);
}

/// Fills 4-wide node `slot` with the children of binary node `b`: its two children, each inner
/// one replaced by its own two while slots remain (the larger box first).
fn collapse(binary: &[Binary], b: usize, nodes: &mut Vec<Node>, slot: usize) {
    let root = &binary[b];
    let mut children: Vec<usize> = if root.count > 0 { vec![b] } else { vec![root.first as usize, root.first as usize + 1] };
    while children.len() < WIDTH {
        let area = |c: usize| {
            let e = binary[c].max - binary[c].min;
            e.x * e.y + e.y * e.z + e.z * e.x
        };
        let Some(at) = (0..children.len()).filter(|&k| binary[children[k]].count == 0).max_by(|&x, &y| area(children[x]).total_cmp(&area(children[y]))) else { break };
        let inner = binary[children[at]].first as usize;
        children.splice(at..=at, [inner, inner + 1]);
    }
    let mut node = Node::EMPTY;
    for (k, &c) in children.iter().enumerate() {
        let child = &binary[c];
        for axis in 0..3 {
            node.lo[axis][k] = child.min[axis];
            node.hi[axis][k] = child.max[axis];
        }
        if child.count > 0 {
            (node.first[k], node.count[k]) = (child.first, child.count);
        } else {
            node.first[k] = nodes.len() as u32;
            nodes.push(Node::EMPTY);
        }
    }
    nodes[slot] = node;
    for (k, &c) in children.iter().enumerate() {
        if binary[c].count == 0 {
            collapse(binary, c, nodes, nodes[slot].first[k] as usize);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Pcg32;

    fn soup(count: usize, rng: &mut Pcg32) -> Vec<Triangle> {
        let mut point = || DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) * 2.0 - DVec3::ONE;
        (0..count)
            .map(|_| {
                let a = point();
                let p = [a, a + 0.2 * point(), a + 0.2 * point()];
                Triangle::new(p, (p[1] - p[0]).cross(p[2] - p[0]).try_normalize().unwrap_or(DVec3::ZERO))
            })
            .collect()
    }

    #[test]
    fn queries_match_every_triangle() {
        // Sizes around the leaf and node widths (one leaf, a partly filled root, deep trees).
        let mut rng = Pcg32::new(5, 3);
        for count in [1, 3, 4, 5, 7, 16, 17, 63, 200, 1000] {
            let triangles = soup(count, &mut rng);
            let (bvh, order) = Bvh::build(&triangles);
            let triangles: Vec<Triangle> = order.iter().map(|&i| triangles[i as usize].clone()).collect();
            let mut found = Vec::new();
            for _ in 0..200 {
                let p = DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) * 4.0 - DVec3::splat(2.0);
                let all: Vec<Closest> = (0..count as u32).map(|i| closest_on_triangle(&triangles[i as usize], p, i)).collect();
                let best = all.iter().copied().reduce(|b, c| if closer(&c, &b) { c } else { b }).unwrap();
                let c = bvh.closest(&triangles, p, Closest::NONE);
                assert_eq!((c.triangle, c.distance_sq), (best.triangle, best.distance_sq), "{count} triangles, closest to {p}");
                let radius = 0.5 * rng.next_f64();
                let within: Vec<u32> = (0..count as u32).filter(|&i| all[i as usize].distance_sq <= radius * radius).collect();
                assert!(bvh.within(&triangles, p, radius, usize::MAX, &mut found));
                assert_eq!(found, within, "{count} triangles within {radius} of {p}");
            }
        }
    }
}
