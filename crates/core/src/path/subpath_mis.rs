//! MIS weights of connections and merges from quantities accumulated along each subpath, so a
//! weight costs O(1) however long the path — the recursion of Georgiev et al.'s VCM (2012; the
//! dVCM, dVC, dVM of their technical report "Implementing Vertex Connection and Merging") written
//! over this project's stored area-measure densities instead of their split cos/d² factors.
//!
//! Notation as in [`Chain`](super::Chain) and [`Densities`](super::Densities): a path x0 … xk,
//! l_i / c_i the light / camera walk's density of x_i, `nee` next-event estimation's of x0,
//! n = M/N the light-tracing count ratio, η = N_VM π r² (`merging`), u(x) the heuristic's power
//! (x² power, x balance, [x > 0] uniform: every weight is 1 / Σ u(ratio), and u is
//! multiplicative, so ratios may be factored). VC(s) is connection technique s (p_s), VM(i)
//! merging at x_i (η ∏_{j≤i} l_j ∏_{j≥i} c_j).
//!
//! **Light side.** Moving the split point down one vertex multiplies the ratio by c_j / l_j
//! (Veach 1997, §10.2). So for a light vertex y_j (j ≥ 1, its predecessors fixed by the walk)
//!
//!   Q_0 = 1 (VC(0), the camera walk hitting x0: its c_0 is zero for delta lights),
//!   Q_j = V_j + u(c_{j−1} / l_{j−1}) · Q_{j−1},
//!   V_j = [VC(j) on] · (j = 1 ? u(nee / l_0) : 1) + [VM(j) on] · u(η l_j),
//!
//! and the light-side sum of VC(s) relative to p_s is u(c_{s−1}/l_{s−1}) · Q_{s−1} (the NEE
//! factor: p_1 / (l_0 ∏_{j≥1} c_j) = nee / l_0). c_{s−1} and c_{s−2} depend on the connection, so a
//! vertex stores l_j, l_{j−1}, Q_{j−1} and V_j, and Q_j is formed only when y_{j+1} exists (it needs
//! c_{j−1}, which the walk fills once it has left y_j).
//!
//! **Camera side.** Moving the split point up multiplies by l_i / c_i: for camera vertex z_m
//! (x_i with i = k − m; z_0 the pinhole)
//!
//!   R(z_0) = 0,
//!   R(z_m) = [VC(i+1) on] · u(n_{i+1}) + [VM(i) on] · u(η c_i) + u(l_{i+1} / c_{i+1}) · R(z_{m−1}),
//!
//! with n_{i+1} = n for i + 1 = k (m = 1: light tracing) and 1 otherwise; the camera-side sum of
//! VC(s) is u(l_s / c_s) · R(x_s) with l_s, l_{s+1} patched by the connection. R(z_m) needs
//! l_{i+1} = pdf_rev of z_{m−1}, filled once the walk has left z_m: it is read only through a
//! successor.
//!
//! **Merging** at x_i: VC(i) / VM(i) = 1 / (η l_i) and VC(i+1) / VM(i) = 1 / (η c_i), so its
//! weight joins the light side of VC(i) and the camera side of VC(i+1), each scaled.
//! Every quantity is f64; a non-finite weight (a zero density where the contribution is zero
//! too) gives 0. `tests` hold every weight to [`Chain::weight`](super::Chain::weight) and to
//! `Densities::vcm_weight` on random chains.

use super::densities::Densities;
use super::merging::{Technique, TechniqueSet};
use super::mis::Heuristic;

/// The techniques of one pass and how they are weighed.
#[derive(Clone, Copy, Debug)]
pub struct SubpathMis {
    heuristic: Heuristic,
    /// 1 with connections (s ≥ 1), else 0.
    vc: f64,
    /// 1 with merging, else 0.
    vm: f64,
    /// η = N_VM π r² (0 without merging).
    eta: f64,
    /// n = M/N.
    light_tracing_ratio: f64,
}

/// What a light-subpath vertex y_j carries into its connections and merges.
#[derive(Clone, Copy, Debug, Default)]
pub struct LightMis {
    /// l_j.
    pub l: f64,
    /// l_{j−1} (0 at y_0).
    pub l_prev: f64,
    /// Q_{j−1} (0 at y_0).
    pub q_prev: f64,
    /// [VC(j) on] · (j = 1 ? u(nee / l_0) : 1).
    pub own_vc: f64,
    /// VM(j) is possible: y_j is a non-delta surface (j ≥ 1).
    pub mergeable: bool,
    /// The walk left y_j through a delta lobe beside smooth ones (plastic): inside a longer
    /// path no technique joins or merges at y_j, so Q_j keeps only the terms below it.
    pub through_delta: bool,
}

/// What a camera-subpath vertex z_m carries into its connections and merges.
#[derive(Clone, Copy, Debug, Default)]
pub struct CameraMis {
    /// c_i = pdf_fwd of z_m (1 at the pinhole).
    pub c: f64,
    /// R(z_m).
    pub r: f64,
    /// [VC(i+1) on] · u(n_{i+1}) (0 at the pinhole).
    pub next_vc: f64,
    /// VM(i) is possible: z_m is a non-delta surface (m ≥ 1).
    pub mergeable: bool,
    /// The walk left z_m through a delta lobe beside smooth ones: R(z_m), read only while z_m is
    /// inside a longer path, keeps only the terms above it (as `LightMis::through_delta`).
    pub through_delta: bool,
}

impl SubpathMis {
    pub fn new(heuristic: Heuristic, set: TechniqueSet, light_tracing_ratio: f64) -> SubpathMis {
        let merging = set.merging_eta > 0.0;
        SubpathMis {
            heuristic,
            vc: if set.connections { 1.0 } else { 0.0 },
            vm: if merging { 1.0 } else { 0.0 },
            eta: if merging { set.merging_eta } else { 0.0 },
            light_tracing_ratio,
        }
    }

    pub fn connections(&self) -> bool {
        self.vc > 0.0
    }

    pub fn merging(&self) -> bool {
        self.vm > 0.0
    }

    /// The heuristic's power of a density ratio.
    #[inline]
    pub fn u(&self, x: f64) -> f64 {
        match self.heuristic {
            Heuristic::Power => x * x,
            Heuristic::Balance => x,
            Heuristic::Uniform => {
                if x > 0.0 {
                    1.0
                } else {
                    0.0
                }
            }
        }
    }

    #[inline]
    fn weight(sum_of_others: f64) -> f64 {
        let w = 1.0 / (1.0 + sum_of_others);
        if w.is_finite() {
            w
        } else {
            0.0
        }
    }

    #[inline]
    fn vm_light(&self, y: &LightMis) -> f64 {
        if y.mergeable {
            self.vm * self.u(self.eta * y.l)
        } else {
            0.0
        }
    }

    #[inline]
    fn vm_camera(&self, z: &CameraMis) -> f64 {
        if z.mergeable {
            self.vm * self.u(self.eta * z.c)
        } else {
            0.0
        }
    }

    /// y_0's record: only l_0 is read.
    pub fn light_origin(&self, l0: f64) -> LightMis {
        LightMis {
            l: l0,
            ..LightMis::default()
        }
    }

    /// Q_j of vertex `y` (j ≥ 1) once the walk has left it, `c_prev` = c_{j−1} as stored.
    pub fn light_q(&self, y: &LightMis, c_prev: f64) -> f64 {
        let own = if y.through_delta {
            0.0
        } else {
            y.own_vc + self.vm_light(y)
        };
        own + self.u(c_prev / y.l_prev) * y.q_prev
    }

    /// The record of light vertex y_j (j ≥ 1) with density `l`, after `prev` = y_{j−1}'s record
    /// and its stored `c_prev_prev` = c_{j−2} (Q_{j−1} = 1 for j = 1). `nee_over_l0`: nee / l_0
    /// of the subpath (read for j = 1); `vertex.vc_valid`: VC(j) can join y_{j−1} and y_j.
    pub fn light_vertex(
        &self,
        j: usize,
        l: f64,
        (prev, c_prev_prev): (&LightMis, f64),
        nee_over_l0: f64,
        vertex: VertexTechniques,
    ) -> LightMis {
        let VertexTechniques {
            vc_valid,
            mergeable,
            through_delta,
        } = vertex;
        let q_prev = if j == 1 {
            1.0
        } else {
            self.light_q(prev, c_prev_prev)
        };
        let own_vc = if vc_valid {
            self.vc * if j == 1 { self.u(nee_over_l0) } else { 1.0 }
        } else {
            0.0
        };
        LightMis {
            l,
            l_prev: prev.l,
            q_prev,
            own_vc,
            mergeable: mergeable && j >= 1,
            through_delta,
        }
    }

    /// The pinhole's record.
    pub fn camera_origin(&self) -> CameraMis {
        CameraMis {
            c: 1.0,
            ..CameraMis::default()
        }
    }

    /// The record of camera vertex z_m (m ≥ 1) with density `c`, after `prev` = z_{m−1}'s record,
    /// whose stored pdf_rev (l of z_{m−1}) is `l_prev`. `vertex.vc_valid`: a connection can join
    /// z_m and z_{m−1}.
    pub fn camera_vertex(
        &self,
        m: usize,
        c: f64,
        (prev, l_prev): (&CameraMis, f64),
        vertex: VertexTechniques,
    ) -> CameraMis {
        let VertexTechniques {
            vc_valid,
            mergeable,
            through_delta,
        } = vertex;
        let n = if m == 1 {
            self.light_tracing_ratio
        } else {
            1.0
        };
        let mut z = CameraMis {
            c,
            r: 0.0,
            next_vc: if vc_valid { self.vc * self.u(n) } else { 0.0 },
            mergeable: mergeable && m >= 1,
            through_delta,
        };
        let own = if through_delta {
            0.0
        } else {
            z.next_vc + self.vm_camera(&z)
        };
        z.r = own + self.u(l_prev / prev.c) * prev.r;
        z
    }

    /// Σ u(p_i / p_s) over the light side of VC(s) whose light end is y = y_{s−1} (s ≥ 2), with
    /// the connection's c_{s−1} and c_{s−2}.
    #[inline]
    fn light_side(&self, y: &LightMis, c: f64, c_prev: f64) -> f64 {
        self.u(c / y.l) * (y.own_vc + self.vm_light(y) + self.u(c_prev / y.l_prev) * y.q_prev)
    }

    /// The camera side of a technique whose lowest camera vertex is z = x_s (t ≥ 2), `z_prev` =
    /// x_{s+1}: `first` = p_{s+1} / p_s (l_s / c_s; l_0 l_1 / (nee c_1) for next-event
    /// estimation), `l_next` = the connection's l_{s+1}.
    #[inline]
    fn camera_side(&self, z: &CameraMis, z_prev: &CameraMis, first: f64, l_next: f64) -> f64 {
        self.u(first) * (z.next_vc + self.vm_camera(z) + self.u(l_next / z_prev.c) * z_prev.r)
    }

    /// VC(s), s ≥ 2, t ≥ 2: light end y_{s−1} = `y`, camera end z_{t−1} = `z`, `z_prev` = z_{t−2};
    /// `d` the densities the connection adds.
    pub fn connection(
        &self,
        y: &LightMis,
        (z, z_prev): (&CameraMis, &CameraMis),
        d: ConnectionDensities,
    ) -> f64 {
        let ConnectionDensities {
            c_y,
            c_y_prev,
            l_z,
            l_z_prev,
        } = d;
        Self::weight(
            self.light_side(y, c_y, c_y_prev) + self.camera_side(z, z_prev, l_z / z.c, l_z_prev),
        )
    }

    /// VC(1), next-event estimation from z = z_{t−1} (k ≥ 2), `z_prev` = z_{t−2}; `d` the
    /// densities the light sample adds.
    pub fn next_event(&self, (z, z_prev): (&CameraMis, &CameraMis), d: NextEventDensities) -> f64 {
        let NextEventDensities {
            nee,
            c0,
            l0,
            l1,
            l_z_prev,
        } = d;
        let camera = self.camera_side(z, z_prev, l0 * l1 / (nee * z.c), l_z_prev);
        Self::weight(self.u(c0 / nee) + camera)
    }

    /// VC(0) with k ≥ 2: the camera walk reached x0 with density `c0`; `x1` = its vertex before
    /// (x1's record, whose R is complete), the light walk's l_0, l_1, next-event estimation's
    /// `nee` of x0 from x1, and whether VC(1) can join them.
    pub fn emitter_hit(
        &self,
        x1: &CameraMis,
        c0: f64,
        l0: f64,
        l1: f64,
        nee: f64,
        vc1_valid: bool,
    ) -> f64 {
        let nee_term = if vc1_valid {
            self.vc * self.u(nee / c0)
        } else {
            0.0
        };
        Self::weight(nee_term + self.u(l0 * l1 / (c0 * x1.c)) * x1.r)
    }

    /// VC(0) with k = 1 (a light seen directly): against light tracing's x0 (l_0) joined to the
    /// pinhole when `vc1_valid`.
    pub fn emitter_seen(&self, c0: f64, l0: f64, vc1_valid: bool) -> f64 {
        if !vc1_valid {
            return 1.0;
        }
        Self::weight(self.vc * self.u(self.light_tracing_ratio * l0 / c0))
    }

    /// VC(k), light tracing from y = y_{s−1}, s = k ≥ 2, with the camera's c_{s−1} and the
    /// connection's c_{s−2}.
    pub fn light_tracing(&self, y: &LightMis, c_y: f64, c_y_prev: f64) -> f64 {
        Self::weight(self.light_side(y, c_y, c_y_prev) / self.u(self.light_tracing_ratio))
    }

    /// VC(1) with k = 1: x0 joined to the pinhole, with the camera walk's c_0 of x0.
    pub fn light_tracing_origin(&self, y0: &LightMis, c0: f64) -> f64 {
        Self::weight(self.u(c0 / (self.light_tracing_ratio * y0.l)))
    }

    /// VM(i): light vertex `y` = y_i merged at camera vertex `z` = z_{t−1} (z_prev = z_{t−2}), with
    /// the merge's c_{i−1} (camera BSDF at z towards y_{i−1}) and l_{i+1} (towards z_{t−2}).
    pub fn merge(
        &self,
        y: &LightMis,
        z: &CameraMis,
        z_prev: &CameraMis,
        c_y_prev: f64,
        l_z_prev: f64,
    ) -> f64 {
        let light = (y.own_vc + self.u(c_y_prev / y.l_prev) * y.q_prev) / self.u(self.eta * y.l);
        let camera = (z.next_vc + self.u(l_z_prev / z_prev.c) * z_prev.r) / self.u(self.eta * z.c);
        Self::weight(light + camera)
    }
}

/// Which techniques a vertex's record allows: whether a connection can join it to the vertex
/// before it (`vc_valid`), whether a merge can happen at it, and whether the walk left it
/// through a delta lobe (see `LightMis`, `CameraMis`).
#[derive(Clone, Copy, Debug)]
pub struct VertexTechniques {
    pub vc_valid: bool,
    pub mergeable: bool,
    pub through_delta: bool,
}

/// The densities a connection VC(s) (s ≥ 2, t ≥ 2) computes at its two ends: on the light side
/// c_{s−1} (`c_y`) and c_{s−2} (`c_y_prev`), on the camera side l_s (`l_z`) and l_{s+1}
/// (`l_z_prev`).
#[derive(Clone, Copy, Debug)]
pub struct ConnectionDensities {
    pub c_y: f64,
    pub c_y_prev: f64,
    pub l_z: f64,
    pub l_z_prev: f64,
}

/// The densities next-event estimation VC(1) computes: x0 drawn with `nee`, its camera density
/// `c0`, the light walk's l_0 and l_1 of x0 and z, and l_2 of z_prev (`l_z_prev`).
#[derive(Clone, Copy, Debug)]
pub struct NextEventDensities {
    pub nee: f64,
    pub c0: f64,
    pub l0: f64,
    pub l1: f64,
    pub l_z_prev: f64,
}

impl SubpathMis {
    /// The records the integrator would build for this path, light vertices x0 … x_{k−1} and camera
    /// vertices z_m = x_{k−m}, m = 0 … k, with the chain's densities as the stored ones.
    fn replay_records(&self, d: &Densities) -> (Vec<LightMis>, Vec<CameraMis>) {
        let mis = self;
        let k = d.k();
        let (l, c, conn) = (&d.light, &d.camera, &d.connectable);
        let mut light = vec![mis.light_origin(l[0])];
        for j in 1..k {
            let c_pp = if j >= 2 { c[j - 2] } else { 0.0 };
            let vertex = VertexTechniques {
                // VC(1) is next-event estimation: the light samples x0 itself (`Chain::valid`).
                vc_valid: if j == 1 {
                    conn[1]
                } else {
                    conn[j - 1] && conn[j]
                },
                mergeable: conn[j],
                // The oracle's `connectable` already says where the path follows a delta lobe.
                through_delta: false,
            };
            let y = mis.light_vertex(j, l[j], (&light[j - 1], c_pp), d.nee / l[0], vertex);
            light.push(y);
        }
        let mut camera = vec![mis.camera_origin()];
        for m in 1..=k {
            let i = k - m;
            let vertex = VertexTechniques {
                vc_valid: conn[i] && conn[i + 1],
                mergeable: conn[i] && i >= 1,
                through_delta: false,
            };
            let z = mis.camera_vertex(m, c[i], (&camera[m - 1], l[i + 1]), vertex);
            camera.push(z);
        }
        (light, camera)
    }

    /// The weight of technique `t` by this recursion, its records built from the from-scratch
    /// densities `d` as the walks would have stored them (`lt mis-check` replays every technique
    /// of a recorded path this way; the tests hold it to `Densities::vcm_weight`).
    pub fn replay(&self, d: &Densities, t: Technique) -> f64 {
        let mis = self;
        let k = d.k();
        let (l, c, conn) = (&d.light, &d.camera, &d.connectable);
        let (ly, cz) = mis.replay_records(d);
        let at = |i: usize| if i <= k { l[i] } else { 0.0 };
        match t {
            Technique::Connect(0) if k == 1 => mis.emitter_seen(c[0], l[0], conn[0] && conn[1]),
            Technique::Connect(0) => mis.emitter_hit(&cz[k - 1], c[0], l[0], l[1], d.nee, conn[1]),
            Technique::Connect(1) if k == 1 => mis.light_tracing_origin(&ly[0], c[0]),
            Technique::Connect(1) => {
                let nd = NextEventDensities {
                    nee: d.nee,
                    c0: c[0],
                    l0: l[0],
                    l1: l[1],
                    l_z_prev: at(2),
                };
                mis.next_event((&cz[k - 1], &cz[k - 2]), nd)
            }
            Technique::Connect(s) if s == k => mis.light_tracing(&ly[k - 1], c[k - 1], c[k - 2]),
            Technique::Connect(s) => {
                let t = k + 1 - s;
                let cd = ConnectionDensities {
                    c_y: c[s - 1],
                    c_y_prev: c[s - 2],
                    l_z: l[s],
                    l_z_prev: at(s + 1),
                };
                mis.connection(&ly[s - 1], (&cz[t - 1], &cz[t - 2]), cd)
            }
            Technique::Merge(i) => {
                mis.merge(&ly[i], &cz[k - i], &cz[k - i - 1], c[i - 1], at(i + 1))
            }
        }
    }
}

#[cfg(test)]
mod tests;
