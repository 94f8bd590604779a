"""The render passes written along paths, part of the Integrator (a mixin of it): Depth, Mist,
Normal, Position, UV, indices, Diffuse Color, denoising features, shader AOVs and Cryptomatte
coverage, per sample at the first surface (or along a chain of passed transparent surfaces),
as Cycles' film writes them."""
from __future__ import annotations

import numpy as np

from .denoise import DenoiseFeatures
from .passes import AOV_CHANNELS, AOV_PREFIX
from .passes import CHANNELS as PASS_CHANNELS
from .passes import DENOISE as DENOISE_PASSES
from .passes import FIRST_SAMPLE
from .sampling import unit_columns
from .specular import view_table
from .surfacevalues import hits_by_material
from .translucency import valid_reflection_normal

F32 = np.float32


# Cycles' CLOSURE_WEIGHT_CUTOFF: a closure lighter than this is not allocated
_WEIGHT_CUTOFF = 1e-5


class PassWriting:
    """A mixin of integrator.Integrator (see the module docstring): its methods read and set
    the Integrator's state."""

    def _pass_normal(self, prim, u, v, ns, ng, I, diffuse, tau=None, scale=None):
        """(3, k) the normal the Normal and Denoising Normal passes take at hits (prim, u, v):
        Cycles' closures' normals averaged by weight, sum w N / sum w (surface_shader_average_normal
        normalizes it, the denoising features do not): the diffuse closures' bent normal
        (weight: the diffuse albedo diffuse (3, k), translucency excluded), the Translucent
        BSDF's raised until its mirror reflection of I clears the surface (its
        maybe_ensure_valid_specular_reflection under Bump Map Correction, bent or smooth: a
        deep bump's Normal.z 0.714 -> 0.777 straight on), the transparent closure's the unbent ns (weight
        tau (3, k) or None). ns and ng face the ray, I (3, k) toward where it came from. The
        layers the albedo folds in (a Principled's specular layer, metal, glass and coat:
        Materials.normal_weights) weigh their own normals, the albedo they add taken from the
        diffuse weight: the specular layer's, metal's, glass's, refraction's and subsurface's
        valid reflection normal, the coat's the unbent ns raised alike (a white specular layer
        over a grey base had left the Normal pass 0.08 off Cycles' under a normal map, a metal
        0.09). scale (k,) or None: what the albedo
        diffuse was scaled by (a cut-out's opacity)."""
        nb, bump = self._bent_normals(prim, u, v, ns, ng, self._back(prim, ng, I))
        if bump is None and not self.mats.any_normal_parts and not self._any_translucent:
            return nb
        folded = None
        mat = np.take(self.tri.material, prim)
        raised = {}

        def raised_of(n):
            # (Cycles' maybe_ensure_valid_specular_reflection of nb or ns, under the material's
            # Bump Map Correction; each computed once)
            key = id(n)
            if key not in raised:
                raised[key] = valid_reflection_normal(ng, I, n, np.take(self.mats.bump_correction, mat))
            return raised[key]
        if self.mats.any_normal_parts:
            weights = np.take(self.mats.normal_weights, mat, axis=1)
            folded = np.take(self.mats.normal_folded, mat, axis=1)
            if self.mats.normal_points:
                self._normal_points(prim, u, v, I, ng, mat, weights, folded)
            diffuse = np.maximum(diffuse - (folded if scale is None else folded * scale), 0.0)
            if self.mats.normal_view is not None:
                # Cycles' weights at the view, a coat's albedo read at its own normal (ns raised):
                # a coat's rim leans to that normal (0.013 off Cycles' pass before)
                mu = np.abs(np.einsum('ij,ij->j', I, raised_of(ns)))
                extra = np.stack([view_table(self.mats.normal_view[r], mat, mu) for r in range(6)])
                weights = np.maximum(weights + extra[:3], 0.0)
                diffuse = np.maximum(diffuse + (extra[3:] if scale is None else extra[3:] * scale), 0.0)
            if scale is not None:
                weights, folded = weights * scale, folded * scale
        parts = [(diffuse.mean(axis=0), nb)]
        if folded is not None:
            if weights[0].any():
                # (Cycles raises a smooth normal too, not only a bent one, under the material's
                # Bump Map Correction: a coarse smooth sphere's rim)
                parts.append((weights[0], raised_of(nb)))
            if weights[1].any():
                # the coat's unbent normal, raised as well (Cycles' Principled: coat_normal =
                # maybe_ensure_valid_specular_reflection(sd, sd->N))
                parts.append((weights[1], raised_of(ns)))
            if weights[2].any():
                # a sheen under a coat: mix(N, sd->N, Coat Weight), its coated share the smooth ns
                parts.append((weights[2], ns))
        if self._any_translucent:
            # (its smooth normal too, as the reflective closures': a smooth-shaded cube's
            # Translucent BSDF had been 0.07 off Cycles' Normal pass per pixel, 26% of pixels
            # more than 0.1, where a Diffuse BSDF's is 0.014)
            wt = self._translucency_at(prim, u, v, self._back(prim, ng, I)).mean(axis=0)
            if scale is not None:
                wt = wt * scale
            if (wt > 0).any():
                parts.append((wt, raised_of(nb)))
        if tau is not None:
            parts.append((tau.mean(axis=0), ns))
        if len(parts) == 1:
            # no closure where the colour is 0 (Cycles allocates none under CLOSURE_WEIGHT_CUTOFF):
            # its average normal is then sd->N, unbent (a normal map under a Base Color that
            # reaches 0 had kept its bent normal, Normal pass 0.45 off Cycles'). The full albedo
            # says whether another layer (a specular one) still carries the bent normal there
            none = parts[0][0] < _WEIGHT_CUTOFF
            if none.any():
                at = np.flatnonzero(none)
                p_at = np.take(prim, at)
                full = np.take(self.mats.base, np.take(self.tri.material, p_at), axis=1)
                self._albedo_maps(p_at, np.take(u, at), np.take(v, at), full,
                                  None if not self._sided else self._back(p_at, ng[:, at], I[:, at]))
                none[at] = full.mean(axis=0) < _WEIGHT_CUTOFF
                return np.where(none, ns, nb).astype(F32)
            return nb
        total = sum(w for w, _ in parts)
        mixed = sum(w * n for w, n in parts) / np.where(total > 0, total, 1.0)
        return np.where(total > 0, mixed, nb).astype(F32)

    def _normal_points(self, prim, u, v, I, ng, mat, weights, folded):
        """Add into weights (3, k) and folded (3, k), in place, what per-point Mix factors
        weigh the hits' folded layers by there (Materials.normal_points: each side's at the
        factor's share, Cycles' closure weights at the point)."""
        back = self._back(prim, ng, I)
        for (_, w_tex, f_tex), sel in zip(self.mats.normal_points,
                                          hits_by_material(mat, [e[0] for e in self.mats.normal_points])):
            if len(sel):
                p, hu, hv = np.take(prim, sel), np.take(u, sel), np.take(v, sel)
                b = None if back is None else np.take(back, sel)
                weights[:, sel] += self._lookup(w_tex, 'Linear', 'REPEAT', None, p, hu, hv, b)
                folded[:, sel] += self._lookup(f_tex, 'Linear', 'REPEAT', None, p, hu, hv, b)

    def _pass_albedo(self, prim, u, v, back):
        """(3, k) the colour the Diffuse Color and Denoising Albedo passes take at hits (prim,
        u, v) (translucency excluded): the albedo, but a rough diffuse's closure colour
        (Materials.pass_base and pass_textures), as Cycles writes its Oren-Nayar closure's weight
        there; the film divides Diffuse Direct and Indirect by it, so their split is Cycles' too."""
        albedo = np.take(self.mats.pass_base, np.take(self.tri.material, prim), axis=1)
        if not self._albedo_varies and not self.mats.pass_textures:
            return albedo
        self._albedo_maps(prim, u, v, albedo, back,
                          textures=self.mats.pass_textures if self.mats.has_pass_colors else None)
        return albedo

    def _write_passes(self, path, hits, hit, data, pix, samp, chain=None, held=None):
        """Data passes from the first visible surface (holdouts and background stay 0); with
        transparent surfaces on the way (chain), as Cycles writes them along it. held (n,) bool
        or None: the held-out surfaces the camera rays met, whose shaders still write their
        AOVs (Cycles evaluates a holdout's shader, AOV nodes included, before the path ends)."""
        if chain:
            return self._write_chain_passes(path, hits, hit, data, pix, samp, chain, held)
        n = len(pix)                                # the block's paths (camera rays: path.pid)
        idx = np.flatnonzero(hit)
        cols = np.take(path.pid, idx)
        want = self.film.passes
        prim = np.take(hits['prim'], idx)
        hu, hv = np.take(hits['u'], idx), np.take(hits['v'], idx)
        if len(idx):
            P, ng, ns, _ = self._surface(hits, idx, path.D)
            side = self._back(prim, ng, -np.take(path.D, idx, axis=1))
            albedo = self._pass_albedo(prim, hu, hv, side)
            # Cycles: the bent normal (with the translucent closure's raised one)
            mean_n = self._pass_normal(prim, hu, hv, ns, ng, -np.take(path.D, idx, axis=1), albedo)
            ns = unit_columns(mean_n)
            if self._any_translucent:                 # Cycles' diffuse closures include it
                albedo += self._translucency_at(prim, hu, hv, self._back(prim, ng, -np.take(path.D, idx, axis=1)))
        else:
            P = ns = mean_n = albedo = np.zeros((3, 0), F32)
            side = None
        if 'UV' in want:
            data['UV'] = np.zeros((3, n), F32)
            data['UV'][:, cols] = self._uv_pass(prim, hu, hv)
        if any(p in want for p in DENOISE_PASSES):    # opaque first surfaces: written there
            if 'DenoiseNormal' in want:
                data['DenoiseNormal'] = np.zeros((3, n), F32)
                data['DenoiseNormal'][:, cols] = DenoiseFeatures.camera_normal(self.camera.to_camera, mean_n,
                                                                                albedo.mean(axis=0))
            if 'DenoiseAlbedo' in want:
                data['DenoiseAlbedo'] = np.zeros((3, n), F32)
                data['DenoiseAlbedo'][:, cols] = albedo
            if 'DenoiseDepth' in want:
                data['DenoiseDepth'] = np.zeros((1, n), F32)
                d = P - np.take(path.O, idx, axis=1)
                data['DenoiseDepth'][0, cols] = np.sqrt(np.einsum('ij,ij->j', d, d))
        if 'Normal' in want:
            data['Normal'] = np.zeros((3, n), F32)
            data['Normal'][:, cols] = ns
        if 'DiffCol' in want:
            data['DiffCol'] = np.zeros((3, n), F32)
            data['DiffCol'][:, cols] = albedo
        if 'Mist' in want:                          # Cycles' mist of the first surface, stored as 1 - mist
            data['Mist'] = np.zeros((1, n), F32)
            data['Mist'][0, cols] = 1.0 - self._mist(P)
        self._write_first(pix, samp, cols, prim, P)
        self._write_coverage(pix, samp, cols, prim, np.ones(len(cols), F32))
        for key, table in self._aovs.items():
            data[key] = np.zeros((table.shape[0], n), F32)
            data[key][:, cols] = self._aov_values(key, table, prim, hu, hv, side)
        self._held_aovs(data, path, hits, held)
        self._world_aov(data, path, hits)

    def _held_aovs(self, data, path, hits, held, done=None):
        """The AOVs the shaders of held-out surfaces write (held: see _write_passes), where the
        pass is not done (done (n,), per block path)."""
        if held is None or not self._aovs or not held.any():
            return
        idx = np.flatnonzero(held)
        cols = np.take(path.pid, idx)
        if done is not None:
            keep = ~done[cols]
            idx, cols = idx[keep], cols[keep]
        prim, u, v = np.take(hits['prim'], idx), np.take(hits['u'], idx), np.take(hits['v'], idx)
        incoming = -np.take(path.D, idx, axis=1)
        side = self._back(prim, incoming, incoming)
        for key, table in self._aovs.items():
            data[key][:, cols] += self._aov_values(key, table, prim, u, v, side)

    def _world_aov(self, data, path, hits, done=None):
        """The world's AOVs added where the block's camera rays missed everything (and their
        pass is not done: done (n,), per block path)."""
        if not self._world_aovs:
            return
        cols = np.take(path.pid, np.flatnonzero(hits['prim'] < 0))
        if done is not None:
            cols = cols[~done[cols]]
        for key, value in self._world_aovs.items():
            data[key][:, cols] += value[:, None]

    def _aov_values(self, key, table, prim, u, v, back=None):
        """(channels, k): what the materials of the surfaces (prim, u, v) write to AOV key: the
        constants of its table (aov_tables) plus what images write there and what inputs
        varying per object or corner write (Geometry.aovs, interpolated). back: the hits' side
        and camera rays (SurfaceValues._back), which chains reading the view need."""
        mat = np.take(self.tri.material, prim)
        out = np.take(table, mat, axis=1)
        corners = self._aov_corners.get(key)
        if corners is not None:
            c = corners.shape[0] // 3
            r = np.take(corners, prim, axis=1)
            out[:c] += r[:c] + r[c:2 * c] * u + r[2 * c:3 * c] * v
        rows, images = self._aov_images[key]
        for m, tex, interp, ext, xf in images:
            sel = np.flatnonzero(mat == m)
            if len(sel):
                rgb = self._lookup(tex, interp, ext, xf, np.take(prim, sel), np.take(u, sel), np.take(v, sel),
                                   None if back is None else back[sel])
                out[:rows, sel] += rgb[:rows]
        return out

    def _write_coverage(self, pix, samp, cols, prim, weight, depth=0):
        """Cryptomatte: the paths cols of the block saw the surfaces prim with weight (k,), as
        the depth-th surface along their camera rays (Cycles' slots go by sample, then depth)."""
        if not self._crypto_ids:
            return
        order = np.take(samp, cols) * _MAX_CHAIN + min(depth, _MAX_CHAIN - 1)
        for kind, tri_ids in self._crypto_ids.items():
            self.film.add_coverage(kind, pix[cols], np.take(tri_ids, prim), weight, order)

    def _uv_pass(self, prim, u, v):
        """Cycles' UV pass at hits (prim, u, v): (u, v, 1) on the active UV map (3,k), 0 on
        meshes without one (primitive_uv)."""
        if self.tri.uvs is None:
            return np.zeros((3, len(prim)), F32)
        tu, tv = self._uv(prim, u, v)
        has = np.ones_like(tu) if self.tri.has_uv is None else np.take(self.tri.has_uv, prim).astype(F32)
        return np.stack([tu, tv, has])

    def _write_first(self, pix, samp, cols, prim, P):
        """The passes Cycles writes from each pixel's sample 0 only (Depth, Position, Object
        and Material Index): of the surfaces prim at points P (3,k) that the paths cols saw;
        the film keeps its background value for the rest."""
        first = np.flatnonzero(samp == 0)
        want = [p for p in FIRST_SAMPLE if p in self.film.passes]
        if not len(first) or not want:
            return
        at = np.full(len(pix), -1, np.int64)      # the block's path -> its column of cols
        at[cols] = np.arange(len(cols))
        rows = np.flatnonzero(at[first] >= 0)     # sample-0 paths that saw a surface
        k = at[first[rows]]
        pixels = pix[first]
        for name in want:
            values = np.full((PASS_CHANNELS[name], len(first)), np.nan, F32)   # nan: background
            if name == 'Depth':
                values[0, rows] = self.camera.z_depth(P[:, k])
            elif name == 'Position':                # world space: the render's centring undone
                values[:, rows] = (P[:, k].astype(np.float64) + self.origin[:, None]).astype(F32)
            elif name == 'IndexOB':
                values[0, rows] = np.take(self._object_pass, np.take(prim, k))
            else:
                values[0, rows] = np.take(self.mats.pass_index, np.take(self.tri.material, np.take(prim, k)))
            self.film.set_first(name, pixels, values)

    def _mist(self, P):
        """Cycles' mist of surface points P (3,k): World > Mist Pass start, depth and falloff."""
        start, depth, falloff = self.settings.mist
        m = np.clip((self.camera.distance(P) - F32(start)) * F32(1.0 / depth if depth > 0 else 0.0), 0.0, 1.0)
        return m ** F32(falloff)

    def _write_chain_passes(self, path, hits, hit, data, pix, samp, chain, held=None):
        """Cycles' data passes for camera rays that met transparent surfaces (film/data_passes.h):
        at every surface of the chain, before its pass-or-stop pick, Diffuse Color adds
        throughput x the surface's diffuse weight and Mist (1 - mist) x mean(throughput x
        alpha); Normal comes from the first surface whose alpha (1 - mean transparency) reaches
        the view layer's Pass Alpha Threshold (0: the first surface), and Depth, Position and
        the indices (sample 0) from that surface, or the last one the chain reached before it
        stopped; a path that passed every surface to the background leaves them at the
        background's values, as in Cycles (0 and 1e10 for Depth; before, they described the
        last surface passed)."""
        n, want = len(pix), self.film.passes
        threshold = float(getattr(self.settings, 'pass_alpha_threshold', 0.5))
        normal, diff, uv = np.zeros((3, n), F32), np.zeros((3, n), F32), np.zeros((3, n), F32)
        mist_out = np.zeros(n, F32)
        aovs = {key: np.zeros((table.shape[0], n), F32) for key, table in self._aovs.items()}
        first_prim = np.full(n, -1, np.int64)       # the surface the sample-0 passes describe
        first_P = np.zeros((3, n), F32)
        done = np.zeros(n, bool)                    # Cycles' PATH_RAY_SINGLE_PASS_DONE
        denoise = DenoiseFeatures(self, n) if any(p in want for p in DENOISE_PASSES) else None
        if denoise is not None:
            denoise.prev[:, path.pid] = path.O      # depth from the ray's origin, then each surface

        bent = 'Normal' in want or denoise is not None

        def surfaces(cols, prim, u, v, thr, alpha, weight, P, ng, ns, I, depth, tau=None):
            albedo = self._pass_albedo(prim, u, v, self._back(prim, ns, I)) * weight     # (ns faces the ray)
            if bent:        # Cycles' Normal and denoising normal: the bent one, as _write_passes,
                # averaged with the transparent closure's (the unbent N) by their weights
                ns = self._pass_normal(prim, u, v, ns, ng, I, albedo, tau, weight)
            if self._any_translucent:
                albedo += self._translucency_at(prim, u, v, self._back(prim, ns, I)) * weight
            if denoise is not None:
                denoise.surface(cols, ns, albedo, P, tau)
            diff[:, cols] += thr * albedo
            if 'Mist' in want:
                mist_out[cols] += (1.0 - self._mist(P)) * (thr * alpha).mean(axis=0)
            # Cryptomatte weighs every surface by throughput x opacity (film/data_passes.h)
            self._write_coverage(pix, samp, cols, prim, thr.mean(axis=0) * alpha.mean(axis=0), depth)
            todo = ~done[cols]
            # Shader AOVs: every surface's shader writes until the pass is done (svm/aov.h)
            side = self._back(prim, I, I) if self._aovs else None
            for key, table in self._aovs.items():
                aovs[key][:, cols[todo]] += self._aov_values(key, table, prim[todo], u[todo], v[todo],
                                                             None if side is None else side[todo])
            first_prim[cols[todo]] = prim[todo]
            first_P[:, cols[todo]] = P[:, todo]
            first = todo & ((alpha.mean(axis=0) >= threshold) | (threshold == 0.0))
            normal[:, cols[first]] = unit_columns(ns[:, first])
            if 'UV' in want:
                uv[:, cols[first]] = self._uv_pass(prim[first], u[first], v[first])
            done[cols[first]] = True

        # Glass is no transparency to the passes: Cycles' refraction is a closure of the surface
        # (its alpha there 1) and the ray past it a transmission ray, which writes none; so each
        # column's later surfaces count by the share of its paths that passed clear (Mist and
        # Depth had described the sky behind a pane: Mist 0.93 where Cycles gives 0.21)
        clear = np.ones(n, F32)
        for depth, c in enumerate(chain):
            cols = np.take(path.pid, c['rows'])
            tau, glass = c['tau'], c['glass']
            alpha = np.clip(1.0 - (tau - glass), 0.0, 1.0)
            share = np.take(clear, cols)
            surfaces(cols, c['prim'], c['u'], c['v'], c['thr'] * share, alpha, c['opacity'], c['P'], c['ng'], c['ns'],
                     -np.take(path.D, c['rows'], axis=1), depth,
                     tau - glass)
            t_mean = tau.mean(axis=0)
            clear[cols] = share * np.where(t_mean > 0, (tau - glass).mean(axis=0) / np.where(t_mean > 0, t_mean, 1.0),
                                           1.0)
        # the surfaces the chain ended on that are not transparent (stops were counted above)
        idx = np.flatnonzero(hit)
        prim = np.take(hits['prim'], idx)
        opaque = ~np.take(self._tri_transparent, prim)
        idx, prim = idx[opaque], prim[opaque]
        if len(idx):
            P, ng, ns, _ = self._surface(hits, idx, path.D)
            thr = np.ones((3, len(idx)), F32) if path.thr is None else np.take(path.thr, idx, axis=1)
            thr = thr * np.take(clear, np.take(path.pid, idx))
            surfaces(np.take(path.pid, idx), prim, np.take(hits['u'], idx), np.take(hits['v'], idx), thr,
                     np.ones((3, len(idx)), F32), np.ones(len(idx), F32), P, ng, ns, -np.take(path.D, idx, axis=1),
                     len(chain))
        if 'Normal' in want:
            data['Normal'] = normal
        if 'DiffCol' in want:
            data['DiffCol'] = diff
        if 'Mist' in want:
            data['Mist'] = mist_out[None, :]
        if 'UV' in want:
            data['UV'] = uv
        if denoise is not None:
            denoise.finish(data)
        data.update(aovs)
        self._held_aovs(data, path, hits, held, done)
        self._world_aov(data, path, hits, done)
        # (paths the roulette ended are not at the background: they keep the last surface reached)
        gone = ~hit if path.dead is None else ~hit & ~path.dead
        if held is not None:        # (a holdout writes none: they keep the last surface passed)
            gone &= ~held
        missed = np.take(path.pid, np.flatnonzero(gone))
        first_prim[missed[~done[missed]]] = -1       # passed every surface below the threshold
        seen = np.flatnonzero(first_prim >= 0)
        self._write_first(pix, samp, seen, first_prim[seen], first_P[:, seen])


# Cryptomatte's arrival order of a sample's surfaces: sample x _MAX_CHAIN + depth along the ray
_MAX_CHAIN = 1 << 12


def aov_tables(aovs, shaders, counts=None) -> dict:
    """{film key 'AOV:<name>': (channels, shaders) float32}: what each shader's AOV Output
    nodes (Material.aovs, or None) write per sample, as Cycles' svm/aov.h: each node a COLOR
    AOV's (r, g, b, 1), so its alpha is the count of nodes writing it (counts: per shader
    Material.aov_counts, or None; absent: 1), a VALUE AOV its value; 0 (alpha 0 too) for
    shaders that write nothing to it."""
    counts = counts if counts is not None else [None] * len(shaders)
    tables = {}
    for name, kind in aovs:
        channels = AOV_CHANNELS[kind][0]
        table = np.zeros((channels, len(shaders)), F32)
        for j, written_by in enumerate(shaders):
            written = (written_by or {}).get(name)
            if written is None:
                continue
            color, value = written
            alpha = float((counts[j] or {}).get(name, 1))
            table[:, j] = (*np.asarray(color, F32)[:3], alpha) if kind == 'COLOR' else (value,)
        tables[AOV_PREFIX + name] = table
    return tables
