//! A bounding-volume hierarchy over a mesh's triangles for closest-point and radius queries:
//! median splits of the centroids along the longest axis, leaves of up to four triangles,
//! children stored in pairs.

use super::triangle::{closer, closest_on_triangle, may_be_within, Closest, Triangle};
use glam::DVec3;

/// Triangles per leaf.
const LEAF_SIZE: usize = 4;

#[derive(Clone, Copy, Debug)]
struct Node {
    min: DVec3,
    max: DVec3,
    /// Inner node: index of the left child (the right one follows it). Leaf: first triangle.
    first: u32,
    /// Triangles in a leaf; 0 for inner nodes.
    count: u32,
}

#[derive(Clone, Debug)]
pub(super) struct Bvh {
    nodes: Vec<Node>,
}

impl Bvh {
    /// Builds the hierarchy over `triangles`; with it, their leaf order (the hierarchy's leaves
    /// refer to the triangles in that order).
    pub fn build(triangles: &[Triangle]) -> (Bvh, Vec<u32>) {
        let mut order: Vec<u32> = (0..triangles.len() as u32).collect();
        let mut nodes = vec![Node { min: DVec3::ZERO, max: DVec3::ZERO, first: 0, count: 0 }];
        let centroids: Vec<DVec3> = triangles.iter().map(|t| (t.p[0] + t.p[1] + t.p[2]) / 3.0).collect();
        fill(&mut nodes, triangles, &centroids, &mut order, 0, 0, triangles.len());
        (Bvh { nodes }, order)
    }

    /// The bounds of every triangle.
    pub fn bounds(&self) -> (DVec3, DVec3) {
        (self.nodes[0].min, self.nodes[0].max)
    }

    /// The closest point of the whole mesh to `p`, starting from `best` (a triangle's closest
    /// point near the answer prunes most of the hierarchy; [`Closest::NONE`] for none).
    pub fn closest(&self, triangles: &[Triangle], p: DVec3, mut best: Closest) -> Closest {
        let mut stack = [0u32; 64];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let node = self.nodes[stack[top] as usize];
            // `>`, not `>=`: a triangle at the same distance with a smaller index wins ties.
            if box_distance_sq(&node, p) > best.distance_sq {
                continue;
            }
            if node.count > 0 {
                for i in node.first..node.first + node.count {
                    if !may_be_within(&triangles[i as usize], p, best.distance_sq) {
                        continue;
                    }
                    let c = closest_on_triangle(&triangles[i as usize], p, i);
                    if closer(&c, &best) {
                        best = c;
                    }
                }
            } else {
                // Visit the nearer child first.
                let (l, r) = (node.first, node.first + 1);
                let (dl, dr) = (box_distance_sq(&self.nodes[l as usize], p), box_distance_sq(&self.nodes[r as usize], p));
                let (near, far) = if dl <= dr { (l, r) } else { (r, l) };
                stack[top] = far;
                stack[top + 1] = near;
                top += 2;
            }
        }
        best
    }

    /// Every triangle within distance `radius` of `p`, or `false` (and a partial list) as soon as
    /// there are more than `max`.
    pub fn within(&self, triangles: &[Triangle], p: DVec3, radius: f64, max: usize, out: &mut Vec<u32>) -> bool {
        out.clear();
        let r2 = radius * radius;
        let mut stack = [0u32; 64];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let node = self.nodes[stack[top] as usize];
            if box_distance_sq(&node, p) > r2 {
                continue;
            }
            if node.count > 0 {
                out.extend((node.first..node.first + node.count).filter(|&i| closest_on_triangle(&triangles[i as usize], p, i).distance_sq <= r2));
                if out.len() > max {
                    return false;
                }
            } else {
                stack[top] = node.first;
                stack[top + 1] = node.first + 1;
                top += 2;
            }
        }
        true
    }
}

fn box_distance_sq(node: &Node, p: DVec3) -> f64 {
    let q = p.clamp(node.min, node.max);
    (p - q).length_squared()
}

/// Fills node `slot` with the hierarchy over `order[first..first + count]`.
fn fill(nodes: &mut Vec<Node>, triangles: &[Triangle], centroids: &[DVec3], order: &mut [u32], slot: usize, first: usize, count: usize) {
    let (mut min, mut max) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    let (mut cmin, mut cmax) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    for &i in &order[first..first + count] {
        for v in triangles[i as usize].p {
            min = min.min(v);
            max = max.max(v);
        }
        cmin = cmin.min(centroids[i as usize]);
        cmax = cmax.max(centroids[i as usize]);
    }
    if count <= LEAF_SIZE {
        nodes[slot] = Node { min, max, first: first as u32, count: count as u32 };
        return;
    }
    let extent = cmax - cmin;
    let axis = if extent.x >= extent.y && extent.x >= extent.z { 0 } else if extent.y >= extent.z { 1 } else { 2 };
    let half = count / 2;
    order[first..first + count].select_nth_unstable_by(half, |&a, &b| centroids[a as usize][axis].total_cmp(&centroids[b as usize][axis]));
    let left = nodes.len();
    nodes.extend([Node { min, max, first: 0, count: 0 }; 2]);
    nodes[slot] = Node { min, max, first: left as u32, count: 0 };
    fill(nodes, triangles, centroids, order, left, first, half);
    fill(nodes, triangles, centroids, order, left + 1, first + half, count - half);
}
