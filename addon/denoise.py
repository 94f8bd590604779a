"""Cycles' Denoising Data passes (normal, albedo, depth) along camera rays through transparent
surfaces (film/denoising_passes.h), for the integrator's data passes. Nothing here knows
Blender."""

import numpy as np

F32 = np.float32


class DenoiseFeatures:
    """Cycles' Denoising Data along a camera ray's surfaces (film/denoising_passes.h): the
    first surface whose diffuse part carries more than a fifth of its closures' sample weight
    (all but a mostly transparent one) writes the camera-space shading normal (x right, y up, z
    into the view; 0 where no closure has weight), the diffuse albedo and the distance from the
    ray's last surface (or origin), all times the features' throughput, the transparency of the
    surfaces it passed before (not divided by the pass probability, as Cycles keeps it); depth
    adds up every surface the features reach. Not followed (Cycles does): a path that stops at a
    mostly transparent surface carries its features on to the next bounce's surface."""

    def __init__(self, integ, n):
        self.to_camera = integ.camera.to_camera.astype(F32)     # world -> Cycles' camera space
        self.want = integ.film.passes
        self.normal, self.albedo = np.zeros((3, n), F32), np.zeros((3, n), F32)
        self.depth = np.zeros(n, F32)
        self.thr = np.ones((3, n), F32)             # Cycles' denoising_feature_throughput
        self.prev = np.zeros((3, n), F32)           # where each camera ray's segment began
        self.done = np.zeros(n, bool)

    @staticmethod
    def camera_normal(to_camera, ns, weight):
        """Shading normals ns (3,k) in Cycles' camera space (to_camera: Camera.to_camera, the
        world -> camera rotation), 0 where the closures' weight (k,) is 0."""
        cam = np.asarray(to_camera, F32) @ ns
        return np.where(weight > 0, cam, F32(0))

    def surface(self, cols, ns, albedo, P, tau=None):
        """Surfaces (ns, diffuse albedo, points P; (3,k)) the paths cols reached; tau (3,k)
        their transparency (None: opaque)."""
        todo = ~self.done[cols]
        # depth at every surface the features reach, before deciding (as Cycles writes it)
        t = np.flatnonzero(todo)
        seg = np.linalg.norm(P[:, t] - self.prev[:, cols[t]], axis=0)
        self.depth[cols[t]] += self.thr[:, cols[t]].mean(axis=0) * seg
        diffuse = albedo.mean(axis=0)
        total = diffuse if tau is None else diffuse + tau.mean(axis=0)
        write = todo & ((total == 0) | (4 * diffuse > total))
        w, c = np.flatnonzero(write), cols[write]
        if 'DenoiseNormal' in self.want:
            self.normal[:, c] = self.camera_normal(self.to_camera, ns[:, w], total[w])
        self.albedo[:, c] = self.thr[:, c] * albedo[:, w]
        self.done[c] = True
        go = np.flatnonzero(todo & ~write)          # mostly transparent: on to the next surface
        if len(go) and tau is not None:
            self.thr[:, cols[go]] *= tau[:, go]
        self.prev[:, cols] = P

    def finish(self, data):
        for name, values in (('DenoiseNormal', self.normal), ('DenoiseAlbedo', self.albedo),
                             ('DenoiseDepth', self.depth[None, :])):
            if name in self.want:
                data[name] = values
