//! The random BSPs of paper 1's Figure 10, shared by the grafted-merge
//! tests and the `merge` benchmark: the leaf holding a random point of the
//! cube `[-half, half]³` is split by a plane through that point with a
//! random normal (integer components up to 2^10), and each new leaf gets a
//! random label below `labels`.

use chisel_bsp::exact::Plane;
use chisel_bsp::tree::{Bsp, Label, Node, NodeId};
use rand::Rng;
use rand_chacha::ChaCha8Rng;

/// A random BSP with `splits` inner nodes in the cube `[-half, half]³`.
pub fn paper_random_bsp(rng: &mut ChaCha8Rng, splits: usize, labels: Label, half: i64) -> Bsp {
    let mut planes: Vec<Plane> = Vec::new();
    let mut nodes = vec![Node::Leaf(rng.random_range(0..labels))];
    while planes.len() < splits {
        let x = [0; 3].map(|_| rng.random_range(-half + 1..half));
        let n = [0; 3].map(|_| rng.random_range(-1024i64..=1024));
        if n == [0; 3] {
            continue;
        }
        let d = -(0..3)
            .map(|i| i128::from(n[i]) * i128::from(x[i]))
            .sum::<i128>();
        let plane = Plane::new(n[0], n[1], n[2], d).expect("small coefficients");
        // The leaf holding x (points on a plane go below).
        let mut at = 0;
        while let Node::Split {
            plane,
            below,
            above,
        } = nodes[at]
        {
            let q = planes[plane as usize];
            let [a, b, c] = q.normal().map(i128::from);
            let value = a * i128::from(x[0]) + b * i128::from(x[1]) + c * i128::from(x[2]);
            at = if value + q.offset() > 0 { above } else { below } as usize;
        }
        let below = nodes.len() as NodeId;
        nodes.push(Node::Leaf(rng.random_range(0..labels)));
        nodes.push(Node::Leaf(rng.random_range(0..labels)));
        nodes[at] = Node::Split {
            plane: planes.len() as u32,
            below,
            above: below + 1,
        };
        planes.push(plane);
    }
    Bsp::from_stored_parts(planes, nodes).expect("a well-formed tree")
}
