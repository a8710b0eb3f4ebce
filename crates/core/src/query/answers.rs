//! One query over a batch of points or rays, by name: the answers of
//! [`SurfaceBvh`]'s batch queries in one type, with the figures a report
//! gives (how many were answered, hits, points inside).

use crate::accel::BATCH_GRAIN;
use crate::hit::Hit;
use crate::query::batch::COHERENT_CHUNK;
use crate::query::closest::ClosestPoint;
use crate::query::surface_bvh::SurfaceBvh;
use crate::ray::Ray;
use glam::Vec3;

/// Which question is asked of each point or ray.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum QueryKind {
    /// Per point: the nearest point of the surface and its triangle.
    Closest,
    /// Per point: the unsigned distance to the surface.
    Distance,
    /// Per point: the distance, negative inside (generalized winding number).
    SignedDistance,
    /// Per point: inside or not, by the generalized winding number
    /// (Jacobson et al. 2013; Barill et al. 2018).
    Inside,
    /// Per ray: the triangles crossed within its interval.
    Count,
    /// Per ray: every hit within its interval, nearest first.
    AllHits,
}

/// The answers of one batch.
#[derive(Clone, Debug, PartialEq)]
pub enum Answers {
    /// Distances ([`QueryKind::Distance`], [`QueryKind::SignedDistance`]).
    Distances(Vec<f32>),
    /// Inside flags.
    Inside(Vec<bool>),
    /// Closest points (`None` where there is no answer).
    Closest(Vec<Option<ClosestPoint>>),
    /// Hit counts.
    Counts(Vec<u32>),
    /// Hit lists, nearest first.
    HitLists(Vec<Vec<Hit>>),
}

impl QueryKind {
    /// The query's name: `closest`, `distance`, `signed-distance`, `inside`,
    /// `count` or `all-hits`.
    pub fn name(self) -> &'static str {
        match self {
            QueryKind::Closest => "closest",
            QueryKind::Distance => "distance",
            QueryKind::SignedDistance => "signed-distance",
            QueryKind::Inside => "inside",
            QueryKind::Count => "count",
            QueryKind::AllHits => "all-hits",
        }
    }

    /// Whether it asks rays (else points).
    pub fn takes_rays(self) -> bool {
        matches!(self, QueryKind::Count | QueryKind::AllHits)
    }
}

impl SurfaceBvh {
    /// Make now what queries of `kind` would otherwise make on their first
    /// use: the point tree for closest points and distances; the
    /// ray-casting tree alone for counts and hit lists; the ray-casting
    /// trees of the surface and of its closing cap for occupancy, with the
    /// point tree and its winding-number moments when the surface's
    /// crossings are not counted (otherwise they are made only if some
    /// point's crossings are too close to an edge to count); both for
    /// signed distance. A one-shot caller can then time building and
    /// answering apart, and a caller that queries one point or ray at a
    /// time from its own parallel loop must call it first (see
    /// [`SurfaceBvh`]).
    pub fn prepare(&self, kind: QueryKind) {
        match kind {
            QueryKind::Distance | QueryKind::Closest => {
                self.points();
            }
            QueryKind::Inside => self.inside_trees(),
            QueryKind::SignedDistance => self.signed_trees(),
            QueryKind::Count | QueryKind::AllHits => {
                self.ray_tree();
            }
        }
    }

    /// Whether the batch query of `kind` on `n` points or rays is a single
    /// task with nothing to make first, so that it starts no parallel work
    /// and may run alone on any thread: up to [`BATCH_GRAIN`] rays over the
    /// ray-casting tree, or up to one Morton-ordered piece of points over
    /// the trees the query walks, once made. For occupancy and signed
    /// distance those include the point tree's winding-number moments even
    /// where the crossings are counted: without them, a point too close to
    /// an edge to count would be summed over the triangles in parallel.
    pub fn single_task(&self, kind: QueryKind, n: usize) -> bool {
        match kind {
            QueryKind::Count | QueryKind::AllHits => n <= BATCH_GRAIN && self.has_ray_tree(),
            QueryKind::Distance | QueryKind::Closest => {
                n <= COHERENT_CHUNK && self.has_point_tree()
            }
            QueryKind::Inside | QueryKind::SignedDistance => {
                n <= COHERENT_CHUNK && self.has_closing() && self.winding_tree_made()
            }
        }
    }

    /// Answer `kind` for every point of `points` (point queries) or every
    /// ray of `rays` (ray queries), keeping at most `max_hits` hits per ray
    /// for [`QueryKind::AllHits`]; parallel over the batch.
    pub fn answer(
        &self,
        kind: QueryKind,
        points: &[Vec3],
        rays: &[Ray],
        max_hits: usize,
    ) -> Answers {
        match kind {
            QueryKind::Distance | QueryKind::SignedDistance => {
                let mut d = vec![0f32; points.len()];
                if kind == QueryKind::Distance {
                    self.distances(points, &mut d)
                } else {
                    self.signed_distances(points, &mut d)
                }
                Answers::Distances(d)
            }
            QueryKind::Inside => {
                let mut inside = vec![false; points.len()];
                self.inside_batch(points, &mut inside);
                Answers::Inside(inside)
            }
            QueryKind::Closest => {
                let mut found = vec![None; points.len()];
                self.closest_points(points, f32::INFINITY, &mut found);
                Answers::Closest(found)
            }
            QueryKind::Count => {
                let mut counts = vec![0u32; rays.len()];
                self.count_hits_batch(rays, &mut counts);
                Answers::Counts(counts)
            }
            QueryKind::AllHits => Answers::HitLists(self.ray_hits_batch(rays, max_hits)),
        }
    }
}

impl Answers {
    /// Points or rays with an answer: a finite distance, a finite point
    /// (inside), a closest point at a finite distance, at least one hit.
    pub fn answered(&self, points: &[Vec3]) -> usize {
        match self {
            Answers::Distances(d) => d.iter().filter(|x| x.is_finite()).count(),
            Answers::Inside(_) => points.iter().filter(|p| p.is_finite()).count(),
            Answers::Closest(c) => c
                .iter()
                .filter(|c| c.is_some_and(|c| c.distance.is_finite()))
                .count(),
            Answers::Counts(c) => c.iter().filter(|&&c| c > 0).count(),
            Answers::HitLists(l) => l.iter().filter(|l| !l.is_empty()).count(),
        }
    }

    /// Hits in all (ray queries).
    pub fn hits(&self) -> Option<u64> {
        match self {
            Answers::Counts(c) => Some(c.iter().map(|&c| u64::from(c)).sum()),
            Answers::HitLists(l) => Some(l.iter().map(|l| l.len() as u64).sum()),
            _ => None,
        }
    }

    /// Points inside (the inside query).
    pub fn inside(&self) -> Option<usize> {
        match self {
            Answers::Inside(i) => Some(i.iter().filter(|&&x| x).count()),
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::TriangleMesh;

    #[test]
    fn answers_match_the_batch_queries_they_name() {
        // A closed tetrahedron; points inside, outside and NaN.
        let mesh = TriangleMesh::new(
            vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z],
            vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
        );
        let bvh = SurfaceBvh::build(&mesh);
        let points = [Vec3::splat(0.1), Vec3::splat(2.0), Vec3::NAN];
        let mut d = vec![0f32; 3];
        bvh.signed_distances(&points, &mut d);
        match bvh.answer(QueryKind::SignedDistance, &points, &[], 0) {
            Answers::Distances(got) => assert_eq!(got[..2], d[..2]),
            other => panic!("{other:?}"),
        }
        let inside = bvh.answer(QueryKind::Inside, &points, &[], 0);
        let mut flags = vec![false; 3];
        bvh.inside_batch(&points, &mut flags);
        assert_eq!(inside, Answers::Inside(flags.clone()));
        assert_eq!(inside.inside(), Some(flags.iter().filter(|&&f| f).count()));
        assert_eq!(inside.answered(&points), 2);
        let rays = [Ray::new(Vec3::new(0.2, 0.2, -1.0), Vec3::Z)];
        let lists = bvh.answer(QueryKind::AllHits, &[], &rays, 8);
        let counts = bvh.answer(QueryKind::Count, &[], &rays, 8);
        assert_eq!(lists.hits(), counts.hits());
        assert_eq!(lists, Answers::HitLists(bvh.ray_hits_batch(&rays, 8)));
    }

    #[test]
    fn prepare_makes_what_the_query_needs_and_changes_no_answer() {
        let sphere = crate::icosphere::Icosphere::new(2);
        let mesh = TriangleMesh::new(sphere.positions.clone(), sphere.indices.clone());
        let points = [Vec3::ZERO, Vec3::splat(0.9), Vec3::splat(2.0)];
        let rays = [Ray::new(Vec3::new(0.1, 0.2, -3.0), Vec3::Z)];
        use QueryKind::*;
        for kind in [Closest, Distance, SignedDistance, Inside, Count, AllHits] {
            let (lazy, ready) = (SurfaceBvh::build(&mesh), SurfaceBvh::build(&mesh));
            ready.prepare(kind);
            // The sphere is closed: its crossings are counted, so occupancy
            // needs no point tree, and rays need none either.
            let points_made = ready.points.get().is_some();
            assert_eq!(
                points_made,
                matches!(kind, Closest | Distance | SignedDistance),
                "{kind:?}"
            );
            let rays_made = ready.rays.get().is_some();
            assert_eq!(rays_made, !matches!(kind, Closest | Distance), "{kind:?}");
            let (built, before) = (ready.bytes(), lazy.bytes());
            assert!(built > before, "{kind:?}: {built} against {before}");
            assert_eq!(
                lazy.answer(kind, &points, &rays, 4),
                ready.answer(kind, &points, &rays, 4),
                "{kind:?}"
            );
            // Answering made nothing that prepare had not.
            assert_eq!(ready.bytes(), built, "{kind:?}");
        }
    }
}
