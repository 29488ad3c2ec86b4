//! Ray queries through Intel Embree (`embree4-sys`, Embree 3.13 or 4.x).
//!
//! One device, one scene, one triangle geometry whose buffers Embree allocates (so Embree owns
//! the padding its SIMD loads need). The scene is built robust (watertight along shared edges,
//! which a renderer needs more than the last few percent of speed) and with high quality.

use super::{
    Accel, AccelError, AnalyticShapes, Coherence, EmbreeIsa, Hit, Ray, TriangleMesh, PACKET_SIZE,
};
use embree4_sys as sys;
use std::mem::size_of;

pub struct EmbreeAccel {
    device: sys::RTCDevice,
    scene: sys::RTCScene,
    /// Face normals indexed by primitive id: `Hit::ng` comes from the mesh, not from Embree's
    /// unnormalised `Ng`, so that both back-ends report identical normals.
    normals: Vec<glam::Vec3>,
    /// Spheres and disks: not in Embree's scene, but tested after it by the same routine as
    /// the obvhs back-end's, so that both answer them identically.
    analytic: AnalyticShapes,
    /// Lanes per Embree packet call: 16 where the CPU traces 16-wide packets natively
    /// (AVX-512), else 8. Embree takes a 16-ray packet on an AVX2 CPU too, but splits it
    /// internally at a cost that makes pairs of `rtcIntersect8` calls faster there
    /// (reports/README.md, "Measurements formerly in code comments (2026-12-07)").
    lanes: usize,
    /// The instruction set the device was created for (`None` where Embree chose).
    isa: Option<EmbreeIsa>,
}

// SAFETY: Embree devices and committed scenes may be used from any thread, and
// `rtcIntersect*`/`rtcOccluded*` on a committed scene are thread-safe (Embree API docs,
// "Thread Safety"). The scene is never modified after `new`, and `Drop` needs `&mut self`.
unsafe impl Send for EmbreeAccel {}
// SAFETY: see `Send`; every `&self` method only queries the committed scene.
unsafe impl Sync for EmbreeAccel {}

impl EmbreeAccel {
    /// Builds the scene over `mesh`. Degenerate triangles are kept (Embree never hits them),
    /// so primitive ids equal indices into `mesh.triangles`. Packets go to Embree in the CPU's
    /// native width ([`Accel::packet_lanes`]).
    pub fn new(mesh: &TriangleMesh) -> Result<Self, AccelError> {
        Self::build(mesh, None, None)
    }

    /// [`EmbreeAccel::new`] with kernels for `isa` (`None`: the best this CPU runs).
    pub fn with_isa(mesh: &TriangleMesh, isa: Option<EmbreeIsa>) -> Result<Self, AccelError> {
        Self::build(mesh, None, isa)
    }

    /// [`EmbreeAccel::new`], with packets handed to Embree `lanes` (8 or 16) rays at a time
    /// whatever the CPU: for tests of both packet paths on one machine.
    pub fn with_lanes(mesh: &TriangleMesh, lanes: usize) -> Result<Self, AccelError> {
        if lanes != 8 && lanes != PACKET_SIZE {
            return Err(AccelError::Embree(format!(
                "packets of {lanes} lanes are not supported (8 or {PACKET_SIZE})"
            )));
        }
        Self::build(mesh, Some(lanes), None)
    }

    fn build(
        mesh: &TriangleMesh,
        lanes: Option<usize>,
        isa: Option<EmbreeIsa>,
    ) -> Result<Self, AccelError> {
        let isa = match isa {
            Some(isa) if !isa.runs_here() => return Err(AccelError::IsaUnsupported(isa)),
            Some(isa) => Some(isa),
            None => EmbreeIsa::best_here(),
        };
        let config = isa.map(|isa| format!("isa={}", isa.name()));
        let config = std::ffi::CString::new(config.unwrap_or_default())
            .map_err(|e| AccelError::Embree(e.to_string()))?;
        // SAFETY: `config` is a NUL-terminated string that outlives the call; Embree copies
        // what it needs of it.
        let device = unsafe { sys::rtcNewDevice(config.as_ptr()) };
        if device.is_null() {
            // SAFETY: with a null device this reads the thread's last device-creation error.
            let code = unsafe { sys::rtcGetDeviceError(std::ptr::null_mut()) };
            return Err(AccelError::Embree(format!(
                "rtcNewDevice failed ({})",
                error_name(code)
            )));
        }
        // SAFETY: `device` is live; these properties are plain queries.
        let (native16, native8) = unsafe {
            (
                sys::rtcGetDeviceProperty(device, sys::RTC_DEVICE_PROPERTY_NATIVE_RAY16_SUPPORTED),
                sys::rtcGetDeviceProperty(device, sys::RTC_DEVICE_PROPERTY_NATIVE_RAY8_SUPPORTED),
            )
        };
        let native = if native16 == 0 && native8 != 0 {
            8
        } else {
            PACKET_SIZE
        };
        // From here on `accel`'s Drop releases the device (and the scene once it exists).
        let mut accel = Self {
            device,
            scene: std::ptr::null_mut(),
            normals: mesh.normals.clone(),
            analytic: mesh.analytic_shapes(),
            lanes: lanes.unwrap_or(native),
            isa,
        };
        accel.build_scene(mesh)?;
        Ok(accel)
    }

    fn build_scene(&mut self, mesh: &TriangleMesh) -> Result<(), AccelError> {
        // SAFETY: `self.device` is live. The buffers are requested with exactly the sizes
        // written below; Embree returns null (checked) when it cannot allocate them.
        unsafe {
            self.scene = sys::rtcNewScene(self.device);
            self.check("rtcNewScene")?;
            sys::rtcSetSceneFlags(self.scene, sys::RTC_SCENE_FLAG_ROBUST);
            sys::rtcSetSceneBuildQuality(self.scene, sys::RTC_BUILD_QUALITY_HIGH);
            if mesh.triangles.is_empty() {
                // Embree rejects empty buffers; an empty scene answers every query with a miss.
                sys::rtcCommitScene(self.scene);
                return self.check("rtcCommitScene");
            }

            let geometry = sys::rtcNewGeometry(self.device, sys::RTC_GEOMETRY_TYPE_TRIANGLE);
            self.check("rtcNewGeometry")?;
            let vertices = sys::rtcSetNewGeometryBuffer(
                geometry,
                sys::RTC_BUFFER_TYPE_VERTEX,
                0,
                sys::RTC_FORMAT_FLOAT3,
                3 * size_of::<f32>(),
                mesh.positions.len(),
            ) as *mut [f32; 3];
            let indices = sys::rtcSetNewGeometryBuffer(
                geometry,
                sys::RTC_BUFFER_TYPE_INDEX,
                0,
                sys::RTC_FORMAT_UINT3,
                3 * size_of::<u32>(),
                mesh.triangles.len(),
            ) as *mut [u32; 3];
            if let Err(err) = self.check("rtcSetNewGeometryBuffer") {
                sys::rtcReleaseGeometry(geometry);
                return Err(err);
            }
            if vertices.is_null() || indices.is_null() {
                sys::rtcReleaseGeometry(geometry);
                return Err(AccelError::Embree(
                    "rtcSetNewGeometryBuffer returned null".into(),
                ));
            }
            for (i, p) in mesh.positions.iter().enumerate() {
                vertices.add(i).write(p.to_array());
            }
            for (i, t) in mesh.triangles.iter().enumerate() {
                indices.add(i).write(*t);
            }
            sys::rtcCommitGeometry(geometry);
            sys::rtcAttachGeometry(self.scene, geometry);
            // The scene holds its own reference from here on.
            sys::rtcReleaseGeometry(geometry);
            self.check("rtcAttachGeometry")?;
            sys::rtcCommitScene(self.scene);
            self.check("rtcCommitScene")
        }
    }

    /// Turns the device's pending error, if any, into an `AccelError` naming `call`.
    fn check(&self, call: &str) -> Result<(), AccelError> {
        // SAFETY: `self.device` is live for the lifetime of `self`.
        let code = unsafe { sys::rtcGetDeviceError(self.device) };
        if code == sys::RTC_ERROR_NONE {
            Ok(())
        } else {
            Err(AccelError::Embree(format!(
                "{call} failed ({})",
                error_name(code)
            )))
        }
    }

    fn hit(&self, t: f32, prim: u32, u: f32, v: f32) -> Hit {
        Hit {
            t,
            prim,
            u,
            v,
            ng: self.normals[prim as usize],
        }
    }
}

impl Drop for EmbreeAccel {
    fn drop(&mut self) {
        // SAFETY: both handles were created in `new` and are released exactly once here;
        // the scene is null only when `new` failed before creating it.
        unsafe {
            if !self.scene.is_null() {
                sys::rtcReleaseScene(self.scene);
            }
            sys::rtcReleaseDevice(self.device);
        }
    }
}

/// Embree's query flags for `coherence`: the coherent flag selects its packet (frustum)
/// traversal for `rtcIntersect16`, faster than the default on camera rays and slower on
/// incoherent rays (reports/README.md, "Measurements formerly in code comments
/// (2026-12-07)").
fn query_flags(coherence: Coherence) -> sys::RTCRayQueryFlags {
    match coherence {
        Coherence::Coherent => sys::RTC_RAY_QUERY_FLAG_COHERENT,
        Coherence::Incoherent => sys::RTC_RAY_QUERY_FLAG_INCOHERENT,
    }
}

fn error_name(code: sys::RTCError) -> &'static str {
    match code {
        sys::RTC_ERROR_NONE => "no error",
        sys::RTC_ERROR_INVALID_ARGUMENT => "invalid argument",
        sys::RTC_ERROR_INVALID_OPERATION => "invalid operation",
        sys::RTC_ERROR_OUT_OF_MEMORY => "out of memory",
        sys::RTC_ERROR_UNSUPPORTED_CPU => "unsupported CPU",
        sys::RTC_ERROR_CANCELLED => "cancelled",
        _ => "unknown error",
    }
}

/// `ray` in Embree's layout; the mask admits every geometry.
fn rtc_ray(ray: &Ray) -> sys::RTCRay {
    sys::RTCRay {
        org_x: ray.origin.x,
        org_y: ray.origin.y,
        org_z: ray.origin.z,
        tnear: ray.tmin,
        dir_x: ray.dir.x,
        dir_y: ray.dir.y,
        dir_z: ray.dir.z,
        time: 0.0,
        tfar: ray.tmax,
        mask: u32::MAX,
        id: 0,
        flags: 0,
    }
}

/// The packet queries for one Embree packet width: `$width` rays go into Embree's SoA
/// layout, with unused and invalid lanes masked off, and come back as hits / blocked flags.
macro_rules! packet_queries {
    ($module:ident, $width:literal, $Valid:ident, $Ray:ident, $RayHit:ident, $Hit:ident,
     $intersect:ident, $occluded:ident) => {
        mod $module {
            use super::{sys, EmbreeAccel, Hit, Ray};

            /// Up to `$width` rays in a packet, with the unused lanes masked off.
            fn packet(rays: &[Ray]) -> (sys::$Valid, sys::$Ray) {
                assert!(
                    rays.len() <= $width,
                    "a packet holds at most {} rays",
                    $width
                );
                let mut packet = sys::$Ray::default();
                let mut valid = sys::$Valid::first(rays.len());
                for (i, ray) in rays.iter().enumerate() {
                    // Invalid rays are masked off, and their lanes keep a harmless ray
                    // (Embree asserts on invalid data): they miss and are blocked.
                    let (origin, dir, tmin, tmax) = if ray.is_valid() {
                        (ray.origin, ray.dir, ray.tmin, ray.tmax)
                    } else {
                        valid.0[i] = 0;
                        (glam::Vec3::ZERO, glam::Vec3::Z, 0.0, 0.0)
                    };
                    packet.org_x[i] = origin.x;
                    packet.org_y[i] = origin.y;
                    packet.org_z[i] = origin.z;
                    packet.tnear[i] = tmin;
                    packet.dir_x[i] = dir.x;
                    packet.dir_y[i] = dir.y;
                    packet.dir_z[i] = dir.z;
                    packet.tfar[i] = tmax;
                    packet.mask[i] = u32::MAX;
                }
                (valid, packet)
            }

            pub(super) fn intersect(
                accel: &EmbreeAccel,
                rays: &[Ray],
                hits: &mut [Option<Hit>],
                flags: sys::RTCRayQueryFlags,
            ) {
                let (valid, ray) = packet(rays);
                let mut rayhit = sys::$RayHit {
                    ray,
                    hit: sys::$Hit::default(),
                };
                rayhit.hit.geomID = [sys::RTC_INVALID_GEOMETRY_ID; $width];
                rayhit.hit.instID[0] = [sys::RTC_INVALID_GEOMETRY_ID; $width];
                let mut args = sys::RTCIntersectArguments::default();
                sys::rtcInitIntersectArguments(&mut args);
                args.flags = flags;
                // SAFETY: `accel.scene` is committed and lives as long as `accel`; `valid` and
                // `rayhit` are aligned for the packet width by their types.
                unsafe { sys::$intersect(&valid, accel.scene, &mut rayhit, Some(&mut args)) };
                let (r, h) = (&rayhit.ray, &rayhit.hit);
                for (i, out) in hits.iter_mut().enumerate() {
                    *out = (valid.0[i] != 0 && h.geomID[i] != sys::RTC_INVALID_GEOMETRY_ID)
                        .then(|| accel.hit(r.tfar[i], h.primID[i], h.u[i], h.v[i]));
                }
            }

            pub(super) fn occluded(accel: &EmbreeAccel, rays: &[Ray], blocked: &mut [bool]) {
                let (valid, mut ray) = packet(rays);
                // SAFETY: as in `intersect`.
                unsafe { sys::$occluded(&valid, accel.scene, &mut ray, None) };
                for (i, out) in blocked.iter_mut().enumerate() {
                    *out = valid.0[i] == 0 || ray.tfar[i] == f32::NEG_INFINITY;
                }
            }
        }
    };
}

packet_queries!(
    packet8,
    8,
    RTCValid8,
    RTCRay8,
    RTCRayHit8,
    RTCHit8,
    rtcIntersect8,
    rtcOccluded8
);
packet_queries!(
    packet16,
    16,
    RTCValid16,
    RTCRay16,
    RTCRayHit16,
    RTCHit16,
    rtcIntersect16,
    rtcOccluded16
);

impl Accel for EmbreeAccel {
    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        if !ray.is_valid() {
            return None;
        }
        let mut rayhit = sys::RTCRayHit {
            ray: rtc_ray(ray),
            hit: sys::RTCHit::default(),
        };
        rayhit.hit.geomID = sys::RTC_INVALID_GEOMETRY_ID;
        rayhit.hit.instID[0] = sys::RTC_INVALID_GEOMETRY_ID;
        // SAFETY: `self.scene` is committed and lives as long as `self`.
        unsafe { sys::rtcIntersect1(self.scene, &mut rayhit, None) };
        let hit = &rayhit.hit;
        let hit = (hit.geomID != sys::RTC_INVALID_GEOMETRY_ID)
            .then(|| self.hit(rayhit.ray.tfar, hit.primID, hit.u, hit.v));
        if self.analytic.is_empty() {
            return hit;
        }
        self.analytic.closest(ray, hit)
    }

    fn occluded(&self, ray: &Ray) -> bool {
        if !ray.is_valid() {
            return true;
        }
        let mut shadow = rtc_ray(ray);
        // SAFETY: as in `intersect`.
        unsafe { sys::rtcOccluded1(self.scene, &mut shadow, None) };
        // Embree marks a blocked ray by setting tfar to -inf.
        shadow.tfar == f32::NEG_INFINITY || self.analytic.occludes(ray)
    }

    fn intersect_packet(&self, rays: &[Ray], hits: &mut [Option<Hit>], coherence: Coherence) {
        assert_eq!(rays.len(), hits.len());
        assert!(
            rays.len() <= PACKET_SIZE,
            "a packet holds at most {PACKET_SIZE} rays"
        );
        let flags = query_flags(coherence);
        if self.lanes == 8 {
            for (rays, hits) in rays.chunks(8).zip(hits.chunks_mut(8)) {
                packet8::intersect(self, rays, hits, flags);
            }
        } else {
            packet16::intersect(self, rays, hits, flags);
        }
        if !self.analytic.is_empty() {
            for (ray, hit) in rays.iter().zip(hits) {
                if ray.is_valid() {
                    *hit = self.analytic.closest(ray, *hit);
                }
            }
        }
    }

    /// Any-hit packets always take Embree's default (hybrid) traversal: with 16-ray calls
    /// its coherent one is slower for them, and with 8-ray calls the two are alike
    /// (reports/README.md, "Measurements formerly in code comments (2026-12-07)").
    fn occluded_packet(&self, rays: &[Ray], blocked: &mut [bool], _: Coherence) {
        assert_eq!(rays.len(), blocked.len());
        assert!(
            rays.len() <= PACKET_SIZE,
            "a packet holds at most {PACKET_SIZE} rays"
        );
        if self.lanes == 8 {
            for (rays, blocked) in rays.chunks(8).zip(blocked.chunks_mut(8)) {
                packet8::occluded(self, rays, blocked);
            }
        } else {
            packet16::occluded(self, rays, blocked);
        }
        for (ray, blocked) in rays.iter().zip(blocked) {
            if !*blocked && !self.analytic.is_empty() {
                *blocked = self.analytic.occludes(ray);
            }
        }
    }

    fn name(&self) -> &'static str {
        "embree"
    }

    fn kernels(&self) -> String {
        match self.isa {
            Some(isa) => format!("embree ({} kernels)", isa.name()),
            None => "embree (kernels of its own choice)".to_string(),
        }
    }

    fn packet_lanes(&self) -> usize {
        self.lanes
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    fn quad() -> TriangleMesh {
        let positions = vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ];
        TriangleMesh::new(positions, vec![[0, 1, 2], [0, 2, 3]])
    }

    #[test]
    fn hits_the_right_triangle_with_embree_barycentrics() {
        let accel = EmbreeAccel::new(&quad()).expect("Embree builds a two-triangle scene");
        let down = Vec3::new(0.0, 0.0, -1.0);
        // (0.75, 0.25) lies in triangle 0 = (v0, v1, v2): p = v0 + u (v1 − v0) + v (v2 − v0)
        // gives u = 0.5, v = 0.25.
        let hit = accel.intersect(&Ray::new(
            Vec3::new(0.75, 0.25, 2.0),
            down,
            0.0,
            f32::INFINITY,
        ));
        let hit = hit.expect("ray through the quad hits");
        assert_eq!(hit.prim, 0);
        assert!((hit.t - 2.0).abs() < 1e-6);
        assert!(
            (hit.u - 0.5).abs() < 1e-6 && (hit.v - 0.25).abs() < 1e-6,
            "{hit:?}"
        );
        assert_eq!(hit.ng, Vec3::Z);
        let hit = accel.intersect(&Ray::new(Vec3::new(0.25, 0.75, 2.0), down, 0.0, 5.0));
        assert_eq!(hit.map(|h| h.prim), Some(1));
        // Outside the quad, and stopped short of it.
        assert!(accel
            .intersect(&Ray::new(Vec3::new(1.5, 0.5, 2.0), down, 0.0, 5.0))
            .is_none());
        assert!(!accel.occluded(&Ray::new(Vec3::new(0.5, 0.5, 2.0), down, 0.0, 1.9)));
        assert!(accel.occluded(&Ray::new(Vec3::new(0.5, 0.5, 2.0), down, 0.0, 2.1)));
    }

    #[test]
    fn empty_mesh_misses_everything() {
        let accel = EmbreeAccel::new(&TriangleMesh::default()).expect("empty scene builds");
        let ray = Ray::new(Vec3::ZERO, Vec3::X, 0.0, f32::INFINITY);
        assert!(accel.intersect(&ray).is_none());
        assert!(!accel.occluded(&ray));
    }
}
