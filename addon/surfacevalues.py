"""Values of a surface at ray hits, part of the Integrator (a mixin of it): hit points and
their side, albedo textures (images, procedurals, attributes), shading normals bent by normal
maps and bump heights (finite differences over the pixel footprint, bump.py), emission at a
point, the texture coordinates a procedural reads (UV, Generated, Object, Position, Normal,
attributes), and Principled alpha; each evaluated for a whole batch of hits (prim, u, v) at
once."""
from __future__ import annotations

import numpy as np

import dacrt

from . import bump as bumpmap
from .cancel import PassCancelled
from .procedural import (ATTRIBUTE_NEED, CAMERA_COORDINATES, SIDED, VIEW, WINDOW_COORDINATES, ProceduralTexels,
                         clip_unit)
from .pathstate import compact
from .sampling import unit_columns
from .viewside import Facing, incoming_of, length_of
from .texture import texture_lookup

F32 = np.float32


class SurfaceValues:
    """A mixin of integrator.Integrator (see the module docstring): its methods read and set
    the Integrator's state."""

    def _surface(self, hits, sel, D):
        """Hit points P, geometric and shading normals facing the incoming rays, and the points
        offset off the surface toward the ray's side (all (3,k)), of the rays sel (None: all)."""
        return dacrt.shading.surface(self.tri.geo, self.tri.normals, hits, sel, D, self.tri.records)

    def _back(self, prim, n, incoming, length=None):
        """(k,) bool: the hits on prim met from behind (n (3, k): the normals turned to face the
        rays, or the rays' directions negated), where a chain reads a normal; else None (no
        material reads the side). incoming (3, k): the rays' directions negated, and length
        (k,): their lengths to the hits (an emitter's callers give them), which it carries
        (viewside.Facing) where a chain reads them (Fresnel, Layer Weight, Light Falloff)."""
        if not self._sided:
            return None
        back = (np.take(self.tri.geo[9:12], prim, axis=1) * n).sum(axis=0) < 0
        return Facing.of(back, incoming, length) if self._viewed else back

    def _albedo_maps(self, prim, u, v, albedo, back=None, textures=None):
        """Multiply what varies over a surface into albedo (3, k) (or a throughput that
        includes it) at hits (prim, u, v), in place: the colour textures (or the entries
        `textures` lists instead, as _texture), then the attribute colours (Geometry.colors)
        of the materials that read one."""
        self._texture(prim, u, v, albedo, textures=textures, back=back)
        if self.tri.colors is not None:
            sel = np.flatnonzero(np.take(self.mats.colored, np.take(self.tri.material, prim)))
            if len(sel):
                p = np.take(prim, sel)
                rows = np.take(self.tri.colors, p, axis=1)
                # interpolated signed, then clamped: Cycles' closure weight is never negative,
                # but its attribute is interpolated before the clamp
                albedo[:, sel] *= np.fmax(rows[0:3] + rows[3:6] * np.take(u, sel) + rows[6:9] * np.take(v, sel),
                                          F32(0.0))

    def _texture(self, prim, u, v, albedo, textures=None, signed=False, back=None):
        """Multiply image textures (on the UV map, through each texture's affine map) into
        albedo (3,k) (or a throughput that includes it) in place: the materials' colour
        textures, or the entries `textures` lists (material, texture, modes) instead. signed:
        negative texels kept (emission), else 0 (albedo); NaN ones are 0 either way."""
        entries = self.mats.textures if textures is None else textures
        if self.tri.uvs is None or not len(entries):
            return
        for (m, tex, interp, ext, xf), sel in zip(entries, hits_by_material(np.take(self.tri.material, prim),
                                                                             [e[0] for e in entries])):
            if len(sel):
                # a texel may be negative (a float image's own values, or a wide-gamut space such
                # as ACEScg converted to scene linear): Cycles' closure weight is not, so a
                # negative blend is 0 there (and NaN too), not a negative albedo
                # (an emission's is not a closure weight: Cycles keeps it signed, so a wide-gamut
                # screen's out-of-gamut texels subtract as there)
                texel = self._lookup(tex, interp, ext, xf, np.take(prim, sel), np.take(u, sel), np.take(v, sel),
                                     None if back is None else np.take(back, sel))
                # (an infinite texel as a NaN one, as Cycles renders both: the blend is inf or NaN
                # there, and Cycles' film drops what it reaches; a kept inf had dropped whole samples
                # here, darkening more than Cycles around it)
                texel = np.where(np.isfinite(texel), texel, F32(0.0))
                albedo[:, sel] *= texel if signed else np.fmax(texel, F32(0.0))

    def _bent_normals(self, prim, u, v, ns, ng, back=None):
        """(shading normals with the materials' normal maps and bump heights applied, bump or
        None): bump (4, k) keeps the smooth normal (rows 0-2) and the Bump Map Correction flag
        (row 3) for the bump shadowing of light samples and bounces; (ns, None) when no material
        bends normals. A Displacement output read as bump sets the shading normal itself first
        (Cycles' SetNormal: closures then shade with it unshadowed, and a normal map does not
        start from it); then the normal map, then the BSDF's Bump nodes. back: the hits' side
        array (_back), for a normal map's colour chain that reads a normal or the view."""
        if not self._bumped:
            return ns, None
        bump = np.empty((4, len(prim)), F32)
        bump[3] = 0.0
        if self._displaced:
            self._undisplaced = True
            try:
                ns = self._bump_mapped(prim, u, v, ns, ng, bump[3], True)
            finally:
                self._undisplaced = False
        bump[:3] = ns
        out = self._normal_mapped(prim, u, v, ns, ng, bump[3], back) if self._normal_mapping else ns
        if self.mats.bumps:
            out = self._bump_mapped(prim, u, v, out, ng, bump[3], False)
        return out, bump

    def _bump_mapped(self, prim, u, v, N, ng, correction, displacement):
        """The normals N (3, k) at hits (prim, u, v) bent by their materials' bump heights
        (bump.bend): the Displacement output's (displacement) or the Bump nodes', in turn. A new
        array where any is bent; correction (k,): those hits' materials' Bump Map Correction."""
        out = None
        for (_, displaced, bumps, corrected), sel in self._bump_hits(self.mats.bumps, prim):
            steps = ((displaced,) if displaced is not None else ()) if displacement else bumps
            if not len(sel) or not steps:
                continue
            if out is None:
                out = np.array(N, F32, copy=True)
            correction[sel] = float(corrected)
            step = max(1, self._PROCEDURAL_CHUNK // 8)
            for a in range(0, len(sel), step):
                if a and self._check_break():
                    raise PassCancelled()
                part = sel[a:a + step]
                p = np.take(prim, part)
                n = np.take(out, part, axis=1)
                behind = (np.take(self.tri.geo[9:12], p, axis=1) * np.take(ng, part, axis=1)).sum(axis=0) < 0
                back = behind if self._sided else None          # (as _back gives it)
                for b in steps:
                    n = self._bumped_normal(b, p, np.take(u, part), np.take(v, part), n, back, behind)
                out[:, part] = n
        return N if out is None else out

    def _bump_hits(self, entries, prim):
        """(entry, indices of the hits on prim of its material) for each of entries (mats.bumps'),
        point-cloud triangles left out: Cycles' points have no surface derivatives, so no bump."""
        for entry, sel in zip(entries, hits_by_material(np.take(self.tri.material, prim), [e[0] for e in entries])):
            if len(sel) and self.tri.unbumped is not None:
                sel = sel[~np.take(self.tri.unbumped, np.take(prim, sel))]
            yield entry, sel

    def _bumped_normal(self, b, prim, u, v, N, back, behind=None):
        """N (3, k) bent by one scenedata.Bump b at hits (prim, u, v): its height's derivatives
        along Cycles' two tap directions (bump.tap_frame) by forward differences over the pixel
        footprint there times the Filter Width (bump.step_lengths; every coordinate moved by its own derivative,
        the normals a chain reads held, as Cycles' bump taps hold N), its strength and distance
        at the hit. behind (k,): the hits met from behind (None: N against the face's normal).

        On a back face Cycles negates dPdu and dPdv (shader_setup_from_ray), so the taps of
        interpolated attributes (UV, Generated, mesh attributes: their du, dv differentials)
        move opposite to the positions' (Object, Position: P + dPdx): a relief of Generated or
        UV heights seen from behind is the front's negated (a bump is a dent there), one of
        Object or Position heights the front's mirrored in N. The attribute taps take the
        mirrored barycentrics there."""
        tex = b.values
        g = np.take(self.tri.geo, prim, axis=1).astype(np.float64)
        if behind is None:
            behind = (g[9:12] * N).sum(axis=0) < 0
        mirrored = [k for k in tex.needs if _interpolated_need(k)] if behind.any() else []
        e1, e2 = g[3:6], g[6:9]
        u64, v64 = u.astype(np.float64), v.astype(np.float64)
        share = b.filter_width
        if not share > 0:                # Cycles' taps at the point itself: no gradient
            return np.asarray(N, F32)
        footprint = self._footprint(g[0:3] + e1 * u64 + e2 * v64)
        step = bumpmap.step_lengths(footprint, self._bump_extent, share)
        area = share * np.asarray(footprint, np.float64) ** 2      # (Cycles' BUMP_DX |det|: bump.bend)
        # the taps along Cycles' frame of the geometric normal on the ray's side (bump.tap_frame),
        # each as the barycentric move that makes it: e1 du + e2 dv = step x T (or B)
        T, B = bumpmap.tap_frame(np.where(behind, -g[9:12], g[9:12]))
        g11, g12, g22 = (e1 * e1).sum(axis=0), (e1 * e2).sum(axis=0), (e2 * e2).sum(axis=0)
        gram = g11 * g22 - g12 * g12
        ok = gram > 0
        gram = np.where(ok, gram, 1.0)

        def barycentric(t):
            a, c = (e1 * t).sum(axis=0) * step, (e2 * t).sum(axis=0) * step
            return np.where(ok, (g22 * a - g12 * c) / gram, 0.0), np.where(ok, (g11 * c - g12 * a) / gram, 0.0)
        centre = self._coordinates32(tex.needs, prim, u64, v64, back)
        values = tex.evaluate(centre)
        held = {k: c for k, c in centre.items() if k in SIDED}

        def height(du, dv):
            coords = self._coordinates32(tex.needs, prim, u64 + du, v64 + dv, back)
            if mirrored:
                across = self._coordinates32(mirrored, prim, u64 - du, v64 - dv, back)
                for k in mirrored:
                    coords[k] = np.where(behind[:, None], across[k], coords[k])
            return tex.evaluate({**coords, **held})[0].astype(np.float64)
        was, self._undisplaced = self._undisplaced, True       # (the taps' normals are the centre's)
        try:
            # forward differences against the centre, as Cycles' two taps (3 evaluations, not 5)
            h_c = values[0].astype(np.float64)
            dh_du = (height(*barycentric(T)) - h_c) / step
            dh_dv = (height(*barycentric(B)) - h_c) / step
        finally:
            self._undisplaced = was
        e1, e2 = T, B                    # (the directions the derivatives are along)
        M = None
        if (b.object_height or b.object_space) and self.tri.tangent_xf is not None:
            M = np.take(self.tri.tangent_xf, np.take(self.tri.instance, prim), axis=0).astype(np.float64)
        if M is None:
            return bumpmap.bend(N, e1, e2, dh_du, dh_dv, values[2], values[1], area=area)
        N64 = np.asarray(N, np.float64)
        MtN = np.einsum('kji,jk->ik', M, N64)                    # M^T N: N in object space
        # (an object-space Displacement's length along N: |M^T N| x (h - mid) x scale)
        factor = np.sqrt((MtN * MtN).sum(axis=0)) if b.object_height else None
        if not b.object_space:
            return bumpmap.bend(N, e1, e2, dh_du, dh_dv, values[2], values[1], factor, area=area)
        Minv = np.linalg.inv(M)
        bent = bumpmap.bend(bumpmap.unit(MtN), np.einsum('kij,jk->ik', Minv, e1), np.einsum('kij,jk->ik', Minv, e2),
                            dh_du, dh_dv, values[2], values[1], factor, area=area)
        return bumpmap.unit(np.einsum('kji,jk->ik', Minv, bent.astype(np.float64)), N64).astype(F32)

    def _footprint(self, P):
        """(k,) the width a camera pixel covers at points P (3, k), Cycles' compact ray
        differential seen from the camera (camera.footprint; at a bounce too, where Cycles'
        own differentials are wider still)."""
        return self.camera.footprint(P)

    def _coordinates32(self, needs, prim, u, v, back):
        """_coordinates at float64 barycentrics (a bump tap's), each (k, 3) float32."""
        return {k: np.ascontiguousarray(c, F32) for k, c in self._coordinates(needs, prim, u, v, back).items()}

    def _normal_mapped(self, prim, u, v, ns, ng, correction, side=None):
        """The shading normals (3, k) at hits (prim, u, v) with their materials' tangent-space
        normal maps applied as Cycles' svm_node_normal_map: c = 2 x texel - 1, its x, y times
        the strength and z mixed from 1, N = normalize(M^-T (c.x T + c.y sign (n x T) + c.z n)),
        all in object space (M the triangle's placement's tangent_xf; world space, M = 1, without one), T
        the interpolated tangent and n the front face's normal (the geometric one, or the corner
        normals interpolated, unnormalized), turned to the side the ray came from as ns is (ng:
        the geometric normal on that side). A new array; hits of other materials keep ns.
        correction (k,): set to each normal-mapped hit's material's Bump Map Correction (0 or 1).
        side: the hits' side array (_back; None: the front), which a per-point colour chain
        reading a normal or the view (Fresnel, Layer Weight) takes."""
        out = np.array(ns, F32, copy=True)
        mat = np.take(self.tri.material, prim)
        t, geo, normals = self.tri.tangents, self.tri.geo, self.tri.normals
        maps = self.mats.normal_maps
        for (m, tex, interp, ext, xf, strength, corrected, space, strength_map), sel in zip(
                maps, hits_by_material(mat, [e[0] for e in maps])):
            if not len(sel):
                continue
            correction[sel] = float(corrected)
            p, uu, vv = np.take(prim, sel), np.take(u, sel), np.take(v, sel)
            at = None if side is None else np.take(side, sel)
            c = F32(2.0) * (self._lookup(tex, interp, ext, xf, p, uu, vv, at) - F32(0.5))
            if strength_map is not None:        # (a Strength driven by nodes: per point, >= 0)
                strength = self._procedural(strength_map, p, uu, vv, at)[0]
            if space != 'TANGENT':
                out[:, sel] = self._direction_mapped(c, space, strength, p, np.take(out, sel, axis=1),
                                                     np.take(ng, sel, axis=1))
                continue
            if t is None:                          # (no mesh had the map's tangents)
                continue
            c[0] *= F32(strength)
            c[1] *= F32(strength)
            c[2] = F32(1.0) + (c[2] - F32(1.0)) * np.minimum(strength, F32(1.0)).astype(F32)
            tr = np.take(t, p, axis=1)
            T = tr[0:4] + tr[4:8] * uu + tr[8:12] * vv          # tangent (0:3) and sign (3)
            M = None if self.tri.tangent_xf is None else \
                np.take(self.tri.tangent_xf, np.take(self.tri.instance, p), axis=0)
            if normals is None:
                n = np.take(geo[9:12], p, axis=1)
                if M is not None:                 # object space: normalize(M^T Ng), as Cycles
                    n = unit_columns(np.einsum('kji,jk->ik', M, n))
            else:
                nr = np.take(normals, p, axis=1)
                corners = (nr[0:3], nr[0:3] + nr[3:6], nr[0:3] + nr[6:9])
                if M is not None:                 # each corner's normal back in object space
                    corners = [unit_columns(np.einsum('kji,jk->ik', M, x)) for x in corners]
                n = corners[0] + (corners[1] - corners[0]) * uu + (corners[2] - corners[0]) * vv
            B = T[3] * np.cross(n, T[:3], axis=0)
            N = c[0] * T[:3] + c[1] * B + c[2] * n
            if M is not None:
                # to world space by the normal matrix: M^-T N = sign(det M) (N.x (b x c) +
                # N.y (c x a) + N.z (a x b)) up to a positive scale, a, b, c the columns of M
                a, b, cc = (np.moveaxis(M[:, :, j], 0, 1) for j in range(3))
                bc, ca, ab = np.cross(b, cc, axis=0), np.cross(cc, a, axis=0), np.cross(a, b, axis=0)
                flip = np.where((a * bc).sum(axis=0) < 0, F32(-1.0), F32(1.0))
                N = (N[0] * bc + N[1] * ca + N[2] * ab) * flip
            length = np.sqrt((N * N).sum(axis=0))
            good = (length > 0) & np.isfinite(length) & (np.abs(T[:3]).sum(axis=0) > 0)
            # back faces: the ray meets the side opposite the winding normal
            back = (np.take(ng, sel, axis=1) * np.take(geo[9:12], p, axis=1)).sum(axis=0) < 0
            N = np.where(back, -N, N) / np.where(good, length, 1)
            out[:, sel] = np.where(good, N, out[:, sel])
        return out

    def _direction_mapped(self, c, space, strength, prim, ns, ng):
        """Shading normals (3, k) of an object- or world-space normal map at hits on prim, as
        Cycles' svm_node_normal_map gives them: c (3, k) = 2 x colour - 1 (y and z negated in
        Blender's own spaces) is the direction, in object space turned to world space by the
        normal matrix M^-T (object_normal_transform), normalized, negated on a back face, then
        normalize(ns + (N - ns) x strength) mixed with the shading normal ns (3, k) (already on
        the ray's side; ng the geometric normal there); ns where the result is zero. strength: a
        number or (k,) per hit."""
        c = np.asarray(c, np.float64)
        if space.startswith('BLENDER_'):
            c = c * np.array([1.0, -1.0, -1.0])[:, None]
        if space.endswith('OBJECT') and self.tri.tangent_xf is not None:
            M = np.take(self.tri.tangent_xf, np.take(self.tri.instance, prim), axis=0).astype(np.float64)
            a, b, cc = (np.moveaxis(M[:, :, j], 0, 1) for j in range(3))
            bc, ca, ab = np.cross(b, cc, axis=0), np.cross(cc, a, axis=0), np.cross(a, b, axis=0)
            flip = np.where((a * bc).sum(axis=0) < 0, -1.0, 1.0)
            c = (c[0] * bc + c[1] * ca + c[2] * ab) * flip          # M^-T c up to a positive scale
        N = bumpmap.unit(c)
        back = (ng * np.take(self.tri.geo[9:12], prim, axis=1)).sum(axis=0) < 0
        N = np.where(back, -N, N)
        n0 = np.asarray(ns, np.float64)
        s = np.maximum(np.asarray(strength, np.float64), 0.0)       # (a number, or (k,) per point)
        if np.any(s != 1.0):
            N = bumpmap.unit(n0 + (N - n0) * s)
        zero = ~(np.abs(N).sum(axis=0) > 0)
        return np.where(zero, n0, N).astype(F32)

    def _emission_at(self, prim, u, v, back=None):
        """Radiance (3, k) of image-emission triangles prim at barycentrics (u, v) (back: the
        hits met from behind, for chains reading a normal; None: the front)."""
        out = np.ones((3, len(prim)), F32)
        self._texture(prim, u, v, out, self.mats.emission_textures, signed=True, back=back)
        return out

    def _textured_samples(self, value, entry, point, origin=None):
        """Scale light samples (value (3, n), in place) that picked an image-emission triangle
        by the image's radiance at the sampled point (point (3, n)), found by its barycentrics;
        origin (3, n): the shading points the samples are seen from (the side of the emitter a
        chain reading its normal sees; None: the front)."""
        tris, r = self.lights.triangles, self.lights.num_lamps
        if tris is None:
            return
        e = entry.astype(np.int64) - r
        idx = np.flatnonzero((e >= 0) & (e < len(tris.index)))
        if not len(idx):
            return
        prim = tris.index[e[idx]]
        keep = np.flatnonzero(self._tri_emit_tex[prim])
        idx, prim = idx[keep], prim[keep]
        if not len(idx):
            return
        g = np.take(self.tri.geo, prim, axis=1).astype(np.float64)
        d = point[:, idx].astype(np.float64) - g[0:3]
        e1, e2 = g[3:6], g[6:9]
        d00, d01, d11 = (e1 * e1).sum(0), (e1 * e2).sum(0), (e2 * e2).sum(0)
        d20, d21 = (d * e1).sum(0), (d * e2).sum(0)
        den = d00 * d11 - d01 * d01
        with np.errstate(divide='ignore', invalid='ignore'):
            bu = np.where(den > 0, (d11 * d20 - d01 * d21) / den, 0.0)
            bv = np.where(den > 0, (d00 * d21 - d01 * d20) / den, 0.0)
        back = None
        if origin is not None and self._sided:
            # (the sample's distance: Cycles' ray_length of a light sample, ls->t)
            seen = origin[:, idx].astype(np.float64) - point[:, idx]
            d = np.sqrt((seen * seen).sum(axis=0))
            back = self._back(prim, seen, seen / np.maximum(d, 1e-30), d)
        value[:, idx] *= self._emission_at(prim, bu.astype(F32), bv.astype(F32), back)

    def _uv(self, prim, u, v):
        """The active UV map's (u, v) (two (k,) arrays) at hits (prim, u, v); (0, 0) without
        a UV map, as Cycles reads a missing attribute."""
        if self.tri.uvs is None:
            return np.zeros(len(prim), F32), np.zeros(len(prim), F32)
        uvc = np.take(self.tri.uvs, prim, axis=1)
        return uvc[0] + uvc[2] * u + uvc[4] * v, uvc[1] + uvc[3] * u + uvc[5] * v

    def _coordinates(self, needs, prim, u, v, back=None):
        """{name: (k, 3) float32} of the texture coordinates `needs` names at hits (prim, u, v):
        'uv' (u, v, 0) of the active UV map, 'generated' and 'object' interpolated from the
        corners (Geometry.coords; 0 where the export gave none, as Cycles reads a missing
        attribute); Cycles' Geometry node's 'position' (the hit point on the triangle, world
        space), 'normal' (the shading normal: the corner normals interpolated and normalized, or
        the face's), 'true_normal' (the face's) and Texture Coordinate's 'object_normal' (the
        object-space corner normals interpolated, normalized; Geometry.coords 6:9), the normals
        turned to the ray's side where back (k,) says it met the back (Cycles' shader setup
        negates N and Ng there); None: the front."""
        out = {}
        if 'parametric' in needs:       # Cycles' Geometry Parametric: (1 - u - v, u, 0)
            uu, vv = np.asarray(u, np.float64), np.asarray(v, np.float64)
            out['parametric'] = np.stack([1.0 - uu - vv, uu, np.zeros_like(uu)], axis=1)
        if 'uv' in needs:
            tu, tv = self._uv(prim, u, v)
            out['uv'] = np.stack([tu, tv, np.zeros_like(tu)], axis=1)
        rows = self.tri.coords
        width = 0 if rows is None else len(rows) // 3
        for k, name in enumerate(('generated', 'object', 'object_normal')):
            if name not in needs:
                continue
            if rows is None or width < 3 * k + 3:
                out[name] = np.zeros((len(prim), 3), F32)
                continue
            # (the three rows of each coefficient taken alone: a take of all the rows had
            # gathered every coordinate's 27 for each one asked for)
            a, b = 3 * k, 3 * k + 3
            c0, cu, cv = (np.take(rows[o + a:o + b], prim, axis=1) for o in (0, width, 2 * width))
            c = c0 + cu * u + cv * v
            if name == 'object_normal':
                c = self._sided_unit(c, back)
            out[name] = np.ascontiguousarray(c.T, F32)
        if CAMERA_COORDINATES in needs:
            g = np.take(self.tri.geo, prim, axis=1).astype(np.float64)
            p = g[0:3] + g[3:6] * u + g[6:9] * v - self.camera.pos[:, None]     # (both recentred)
            out[CAMERA_COORDINATES] = np.ascontiguousarray((self.camera.to_camera @ p).T, F32)
        if WINDOW_COORDINATES in needs:
            g = np.take(self.tri.geo, prim, axis=1).astype(np.float64)
            p = g[0:3] + g[3:6] * u + g[6:9] * v - self.camera.pos[:, None]
            out[WINDOW_COORDINATES] = np.ascontiguousarray(self.camera.window(p).T, F32)
        if 'edge_distance' in needs:
            out['edge_distance'] = self._edge_distance(prim, u, v)
        if 'position' in needs or 'normal' in needs or 'true_normal' in needs:
            g = np.take(self.tri.geo, prim, axis=1)
            if 'position' in needs:
                p = g[0:3].astype(np.float64) + g[3:6] * u + g[6:9] * v + self.origin[:, None]
                out['position'] = np.ascontiguousarray(p.T, F32)
            if 'true_normal' in needs:
                out['true_normal'] = np.ascontiguousarray(self._sided_unit(g[9:12], back).T, F32)
            if 'normal' in needs:
                out['normal'] = np.ascontiguousarray(self._shading_normal(prim, u, v, back, g).T, F32)
        if not VIEW.isdisjoint(needs):
            self._view_coordinates(out, needs, len(prim), back)
        if self._displaced and not self._undisplaced and ('normal' in out or 'object_normal' in out):
            self._displace_coordinates(out, prim, u, v, back)
        # per-object values (Object Info outputs): the hit triangle's placement's; mesh
        # attributes (procedural.ATTRIBUTE_NEED): their RGBA interpolated from the corners
        for name in needs:
            if isinstance(name, str) and name in self.tri.instance_values:
                out[name] = self.tri.instance_values[name][self.tri.instance[prim]]
            elif isinstance(name, str) and name.startswith(ATTRIBUTE_NEED):
                rows = self.tri.attributes.get(name)
                if rows is None:         # (no triangle reads it: what Cycles reads of a missing one)
                    a = np.zeros((len(prim), 4), F32)
                    a[:, 3] = 1.0
                else:
                    r = np.take(rows, prim, axis=1)
                    a = np.ascontiguousarray((r[0:4] + r[4:8] * u + r[8:12] * v).T, F32)
                out[name] = a
        return out

    def _edge_distance(self, prim, u, v):
        """(k, 1) float32 the squared distance from hits (prim, u, v) to the nearest line through an
        edge of their triangle (world space), which the Wireframe node compares with (Size / 2)^2:
        Cycles' svm_wireframe, |edge x (P - corner)|^2 against |edge|^2 (Size / 2)^2 for each edge
        (a zero-length edge is no line: infinitely far)."""
        g = np.take(self.tri.geo, prim, axis=1).astype(np.float64)
        e1, e2 = g[3:6], g[6:9]
        p = e1 * u + e2 * v                      # the hit, from the triangle's first corner
        corners = (np.zeros_like(e1), e1, e2)
        best = np.full(len(prim), np.inf)
        with np.errstate(divide='ignore', invalid='ignore'):
            for i in range(3):
                edge = corners[i] - corners[i - 1]
                crs = np.cross(edge, p - corners[i], axis=0)
                d2 = (crs * crs).sum(axis=0) / (edge * edge).sum(axis=0)
                best = np.fmin(best, np.where(np.isfinite(d2), d2, np.inf))
        return best.astype(F32).reshape(-1, 1)

    @staticmethod
    def _view_coordinates(out, needs, k, back):
        """What the hits' rays give (procedural.VIEW, into out): the Fresnel and Layer Weight
        nodes' 'incoming' (k, 3) and 'backfacing' (k, 1), an emission's Light Falloff's
        'ray_length' (k, 1), from the side array back (viewside.Facing) the hits' caller made:
        every caller of a chain that reads them gives their rays (Integrator._back), and the
        emitters' callers their lengths."""
        incoming, length = incoming_of(back), length_of(back)
        if incoming is None or incoming.shape[-1] != k or ('ray_length' in needs and length is None):
            raise ValueError("a chain reads the hits' rays (Fresnel, Layer Weight, Light Falloff) where they "
                             "were not given")
        if 'incoming' in needs:
            out['incoming'] = np.ascontiguousarray(incoming.T, F32)
        if 'backfacing' in needs:
            out['backfacing'] = np.asarray(back, F32).reshape(-1, 1)
        if 'ray_length' in needs:
            out['ray_length'] = np.asarray(length, F32).reshape(-1, 1)

    def _shading_normal(self, prim, u, v, back, g=None):
        """(3, k) the shading normal at hits (prim, u, v): the corner normals interpolated and
        normalized, or the face's; negated where back."""
        if self.tri.normals is None:
            n = (np.take(self.tri.geo, prim, axis=1) if g is None else g)[9:12]
        else:
            nr = np.take(self.tri.normals, prim, axis=1)
            n = nr[0:3] + nr[3:6] * u + nr[6:9] * v
        return self._sided_unit(n, back)

    def _displace_coordinates(self, out, prim, u, v, back):
        """Cycles sets a Displacement output's bump as the shader's N before the surface's nodes
        run: Geometry Normal and Texture Coordinate Normal (normalize(M^T N), the placement's
        linear map M) of the hits of displaced materials read it (coordinates out, in place)."""
        entries = [e for e in self.mats.bumps if e[1] is not None]
        for (_, displaced, _, _), sel in self._bump_hits(entries, prim):
            if not len(sel):
                continue
            p, uu, vv = np.take(prim, sel), np.take(u, sel), np.take(v, sel)
            bk = None if back is None else np.take(back, sel)
            N = out['normal'][sel].T if 'normal' in out else self._shading_normal(p, uu, vv, bk)
            self._undisplaced = True
            try:
                bent = self._bumped_normal(displaced, p, uu, vv, np.asarray(N, F32), bk)
            finally:
                self._undisplaced = False
            if 'normal' in out:
                out['normal'][sel] = bent.T
            if 'object_normal' in out and self.tri.tangent_xf is not None:
                M = np.take(self.tri.tangent_xf, np.take(self.tri.instance, p), axis=0).astype(np.float64)
                out['object_normal'][sel] = bumpmap.unit(np.einsum('kji,jk->ik', M, bent.astype(np.float64))).T

    @staticmethod
    def _sided_unit(n, back):
        """n (3, k) normalized (a zero one stays 0) and negated where back."""
        length = np.sqrt((n * n).sum(axis=0))
        n = n / np.where(length > 0, length, 1)
        return n if back is None else np.where(back, -n, n)

    def _lookup(self, tex, interp, ext, xf, prim, u, v, back=None):
        """RGB (3,k) of a texture at hits (prim, u, v) on the UV map (no UV map: (0, 0), as
        Cycles reads a missing attribute), through its affine map xf (or None); a procedural
        texture at the hits' texture coordinates."""
        if isinstance(tex, ProceduralTexels):
            return self._procedural(tex, prim, u, v, back)
        tu, tv = self._uv(prim, u, v)
        if xf is not None:
            tu, tv = xf[0, 0] * tu + xf[0, 1] * tv + xf[0, 2], xf[1, 0] * tu + xf[1, 1] * tv + xf[1, 2]
        return texture_lookup(tex, tu, tv, interp, ext)

    # points a procedural texture is evaluated at between cancel polls: a 3D Gabor texture takes
    # ~35 us a point in numpy, so a bounce's hits at once had kept Esc waiting for many seconds
    _PROCEDURAL_CHUNK = 32768

    def _procedural(self, tex, prim, u, v, back=None):
        """RGB (3,k) of a procedural texture at hits (prim, u, v), in chunks with Esc polled
        between them (the pass is then dropped, as at a bounce)."""
        n, step = len(prim), self._PROCEDURAL_CHUNK
        if n <= step:
            return tex.evaluate(self._coordinates(tex.needs, prim, u, v, back))
        out = np.empty((3, n), F32)
        for a in range(0, n, step):
            if a and self._check_break():
                raise PassCancelled()
            b = min(n, a + step)
            out[:, a:b] = tex.evaluate(self._coordinates(tex.needs, prim[a:b], u[a:b], v[a:b],
                                                         None if back is None else back[a:b]))
        return out


    def _transparency(self, prim, u, v, back=None):
        """At hits (prim, u, v) on transparent triangles: the weight rays pass with (3,k) and
        the opacity (k,) the rest of the shader carries (1 but under opacity textures; the
        opaque part's own glass passes at that opacity, the transparency at 1 - opacity).
        Materials that share an opacity texture (one image's alpha) are looked up together:
        a transparent step pays per texture, not per material (mats.opacity_groups)."""
        mat = np.take(self.tri.material, prim)
        tau = np.take(self.mats.transparency, mat, axis=1)
        opacity = np.ones(len(prim), F32)
        groups = self.mats.opacity_groups
        if not groups:
            return tau, opacity, mat
        group = np.take(self.mats.opacity_group, mat)
        first = int(group[0]) if len(group) else -1
        if first >= 0 and (group == first).all():      # (a camera ray's layer: often one texture)
            found = [(groups[first][0], None)]
        else:
            found = [(g[0], sel) for g, sel in zip(groups, hits_by_material(group, range(len(groups)))) if len(sel)]
        textured = None                                 # the hits under an opacity texture
        for (tex, interp, ext, xf), sel in found:
            p, uu, vv, bk = (prim, u, v, back) if sel is None else compact(sel, prim, u, v, back)
            if sel is not None and incoming_of(back) is not None:     # (the native take drops the view)
                bk = np.take(back, sel)
            a = clip_unit(self._lookup(tex, interp, ext, xf, p, uu, vv, bk)[0], 1.0)    # a NaN texel: opaque
            if a.dtype != F32:                          # (blended as it came, before the cast)
                at = slice(None) if sel is None else sel
                glass = np.take(self.mats.opaque_refraction, mat[at], axis=1)
                tau[:, at] = tau[:, at] * (1.0 - a) + glass * a
            if sel is None:
                opacity[:] = a
                textured = None if a.dtype != F32 else slice(None)
            else:
                opacity[sel] = a
                if a.dtype == F32:
                    textured = sel if textured is None else np.concatenate([textured, sel])
        # the rest passes at 1 - opacity, the opaque part's own glass at opacity: one pass for all
        if textured is not None:
            a = opacity[textured]
            glass = np.take(self.mats.opaque_refraction, mat[textured], axis=1)
            tau[:, textured] = tau[:, textured] * (1.0 - a) + glass * a
        return tau, opacity, mat


def _interpolated_need(name):
    """Whether a texture coordinate is a corner attribute interpolated over the triangle in
    Cycles (UV, Generated, mesh attributes), whose bump taps follow du, dv, rather than one of
    the hit position (Object, Position)."""
    return name in ('uv', 'generated') or (isinstance(name, str) and name.startswith(ATTRIBUTE_NEED))


def hits_by_material(mat, materials):
    """For each material of the list, the indices (ascending) of the hits mat (k,) on it: one
    sort for all where the list is long (a scan of every hit per material had made a frame of
    3000 image-textured materials spend 3.8 s in Python), one scan each where it is short."""
    if len(materials) <= 4:
        return [np.flatnonzero(mat == m) for m in materials]
    order = np.argsort(mat, kind='stable')
    ranked = mat[order]
    keys = np.asarray(materials, ranked.dtype)
    lo, hi = np.searchsorted(ranked, keys, 'left'), np.searchsorted(ranked, keys, 'right')
    return [order[a:b] for a, b in zip(lo.tolist(), hi.tolist())]
