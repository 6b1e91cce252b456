// r1 view: the epoch drawn with WebGL2 and R-1.0 9's navigation (spec/viewer.md). The navigation
// rules are ports of reference/render/navigation.cpp, line for line, so the browser tests can
// compare this page's cameras with the reference's; window.r1view is the testing hook.
'use strict';
(() => {
  // ---- vectors and quaternions (as r1::render::Vec3 / Quat) --------------------------------------
  const add = (a, b) => [a[0] + b[0], a[1] + b[1], a[2] + b[2]];
  const sub = (a, b) => [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
  const mul = (a, s) => [a[0] * s, a[1] * s, a[2] * s];
  const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
  const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
  const len = (a) => Math.sqrt(dot(a, a));
  const norm = (a) => { const l = len(a); return [a[0] / l, a[1] / l, a[2] / l]; };
  // v + 2 w (q x v) + q x (2 q x v): Quat::rotate, the same operations in the same order.
  function rotate(q, v) {
    const u = [q[1], q[2], q[3]];
    const t = mul(cross(u, v), 2.0);
    return add(add(v, mul(t, q[0])), cross(u, t));
  }
  function qmul(a, b) {
    return [a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
            a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
            a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
            a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0]];
  }
  function qnormalize(q) { const l = Math.hypot(q[0], q[1], q[2], q[3]); return q.map((c) => c / l); }
  function axisAngle(axis, angle) {
    const s = Math.sin(angle / 2);
    return [Math.cos(angle / 2), axis[0] * s, axis[1] * s, axis[2] * s];
  }
  // look_at (reference/render/view.cpp): Shepperd's method on the camera-to-scene rotation.
  function lookAt(eye, target, up) {
    const fwd = sub(target, eye);
    if (!(len(fwd) > 0)) return null;
    const f = norm(fwd);
    const side = cross(f, up);
    if (!(len(side) > 1e-9 * len(up))) return null;
    const r = norm(side);
    const u = cross(r, f);
    const m00 = r[0], m01 = u[0], m02 = -f[0];
    const m10 = r[1], m11 = u[1], m12 = -f[1];
    const m20 = r[2], m21 = u[2], m22 = -f[2];
    const trace = m00 + m11 + m22;
    let q;
    if (trace > 0) {
      const s = Math.sqrt(trace + 1.0) * 2;
      q = [0.25 * s, (m21 - m12) / s, (m02 - m20) / s, (m10 - m01) / s];
    } else if (m00 > m11 && m00 > m22) {
      const s = Math.sqrt(1.0 + m00 - m11 - m22) * 2;
      q = [(m21 - m12) / s, 0.25 * s, (m01 + m10) / s, (m02 + m20) / s];
    } else if (m11 > m22) {
      const s = Math.sqrt(1.0 + m11 - m00 - m22) * 2;
      q = [(m02 - m20) / s, (m01 + m10) / s, 0.25 * s, (m12 + m21) / s];
    } else {
      const s = Math.sqrt(1.0 + m22 - m00 - m11) * 2;
      q = [(m10 - m01) / s, (m02 + m20) / s, (m12 + m21) / s, 0.25 * s];
    }
    return qnormalize(q);
  }

  // ---- state ---------------------------------------------------------------------------------------
  const WARP_SECONDS = 0.5, STAND_OFF = 3.0;
  const S = {
    meta: null, gen: 0, n: 0, m: 0,
    pos: null, radius: null, phi: null, color: null, edges: null, weights: null, labels: [],
    incident: null,       // {offset, edge}: index_edges
    cam: { position: [0, 0, 2500], orientation: [1, 0, 0, 0], fov: 50 },
    width: 0, height: 0, fixedSize: false,
    keys: new Set(), flights: [], portal: null,
    content: new Map(),   // particle -> its T0 content entry of meta.json (R1-VIEW-070)
    contentTex: new Map(), // particle -> {tex, w, h, page}: its content as a texture (R1-VIEW-073)
    contentDrawn: 0,       // T0 particles whose content the last frame drew
    frameMs: 0, lastFrame: 0, tierCounts: [0, 0, 0, 0, 0], visible: 0, labelsDrawn: 0,
    transition: null,     // {from: Float64Array, start, seconds}: positions easing into a new generation
    shown: null,          // the positions drawn: pos, or the eased ones during a transition
    time: 0, frozenTime: null,
    pending: [],          // resolvers waiting for the next drawn frame
  };

  // ---- navigation (ports of reference/render/navigation.cpp) -----------------------------------
  const smoothstep = (x) => { const t = Math.min(Math.max(x, 0), 1); return t * t * (3.0 - 2.0 * t); };
  const P = (p) => [S.pos[3 * p], S.pos[3 * p + 1], S.pos[3 * p + 2]];

  function warpEnd(from, p) {
    const x = P(p);
    const tiny = 1e-9 * S.meta.scene_radius;
    let d = sub(from.position, x);
    if (!(len(d) > tiny)) d = sub(x, S.meta.centroid);
    const n = len(d) > tiny ? norm(d) : [0, 0, 1];
    const to = { position: add(x, mul(n, STAND_OFF * S.radius[p])), orientation: from.orientation.slice(), fov: from.fov };
    for (const up of [rotate(from.orientation, [0, 1, 0]), [0, 0, 1], [0, 1, 0]]) {
      const q = lookAt(to.position, x, up);
      if (q) { to.orientation = q; break; }
    }
    return to;
  }
  function warpAt(from, to, t) {
    if (t >= WARP_SECONDS) return { position: to.position.slice(), orientation: to.orientation.slice(), fov: to.fov };
    const s = smoothstep(t / WARP_SECONDS);
    const a = from.orientation;
    let b = to.orientation;
    if (a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3] < 0) b = b.map((c) => -c);
    const q = [a[0] + (b[0] - a[0]) * s, a[1] + (b[1] - a[1]) * s, a[2] + (b[2] - a[2]) * s, a[3] + (b[3] - a[3]) * s];
    const l = Math.sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    return { position: add(from.position, mul(sub(to.position, from.position), s)),
             orientation: [q[0] / l, q[1] / l, q[2] / l, q[3] / l], fov: from.fov + (to.fov - from.fov) * s };
  }
  function nearestParticle(x) {
    let best = 0, bestD = Infinity;
    const pos = S.pos;
    for (let p = 0; p < S.n; ++p) {
      const dx = pos[3 * p] - x[0], dy = pos[3 * p + 1] - x[1], dz = pos[3 * p + 2] - x[2];
      const dd = dx * dx + dy * dy + dz * dz;
      if (dd < bestD) { bestD = dd; best = p; }
    }
    return best;
  }
  function indexEdges() {
    const offset = new Uint32Array(S.n + 1);
    for (let k = 0; k < S.m; ++k) { ++offset[S.edges[2 * k] + 1]; ++offset[S.edges[2 * k + 1] + 1]; }
    for (let p = 0; p < S.n; ++p) offset[p + 1] += offset[p];
    const edge = new Uint32Array(offset[S.n]);
    const fill = offset.slice(0, S.n);
    for (let k = 0; k < S.m; ++k) { edge[fill[S.edges[2 * k]]++] = k; edge[fill[S.edges[2 * k + 1]]++] = k; }
    return { offset, edge };
  }
  function heaviestNeighbour(p) {
    let best = -1, bestW = 0;
    const ix = S.incident;
    for (let k = ix.offset[p]; k < ix.offset[p + 1]; ++k) {
      const e = ix.edge[k];
      const q = S.edges[2 * e] === p ? S.edges[2 * e + 1] : S.edges[2 * e];
      const w = S.weights[e];
      if (best < 0 || w > bestW || (w === bestW && q < best)) { best = q; bestW = w; }
    }
    return best;
  }
  function flightSpeed(x) {
    const p = nearestParticle(x);
    const d = len(sub(P(p), x));
    return Math.min(Math.max(d, 2.0 * S.radius[p]), S.meta.scene_radius);
  }
  function followFlowStep(c, vUser, dt) {
    let v = vUser.slice();
    const p = nearestParticle(c.position);
    const q = heaviestNeighbour(p);
    if (q >= 0) {
      const d = sub(P(q), c.position);
      if (len(d) > 0) v = add(v, mul(norm(d), flightSpeed(c.position)));
    }
    return { position: add(c.position, mul(v, dt)), orientation: c.orientation.slice(), fov: c.fov };
  }
  // 9.5 (spec/render.md R1-RND-050): tau0 (1 + |camera - centroid| / R_scene)^2.
  function tauCam(c) {
    const g = 1 + len(sub(c.position, S.meta.centroid)) / S.meta.scene_radius;
    return S.meta.tau0 * g * g;
  }
  const focalPx = (c) => cameraFrame(c).focal;

  // ---- loading -------------------------------------------------------------------------------------
  async function fetchArray(gen, name, Type) {
    const r = await fetch(`data/${gen}/${name}`);
    if (!r.ok) throw new Error(`${name}: HTTP ${r.status}`);
    return Type === String ? r.text() : new Type(await r.arrayBuffer());
  }
  async function loadGeneration(meta) {
    const g = meta.generation;
    const names = new Set(meta.arrays.map((a) => a.name));
    const want = [['pos', 'positions.f64', Float64Array], ['radius', 'radius.f64', Float64Array], ['phi', 'phi.f64', Float64Array],
                  ['color', 'color.f32', Float32Array], ['edges', 'edges.u32', Uint32Array], ['weights', 'weights.f64', Float64Array],
                  ['a2', 'a2.f64', Float64Array], ['degree', 'degree.f64', Float64Array], ['clusters', 'clusters.u32', Uint32Array],
                  ['nodes', 'nodes.f64', Float64Array], ['shape', 'shape.u8', Uint8Array], ['labels', 'labels.txt', String]];
    if (names.has('prev.u32')) want.push(['prev', 'prev.u32', Uint32Array]);
    const got = await Promise.all(want.map(([, name, Type]) => fetchArray(g, name, Type)));
    const d = { meta, prev: null };
    want.forEach(([key], i) => { d[key] = got[i]; });
    d.labels = d.labels.split('\n');
    return d;
  }
  function install(d) {
    // The switch is whole (R-1.0 2's double buffer): every array of the new generation at once.
    let from = null;
    if (S.pos && d.prev) {
      from = new Float64Array(d.pos.length);
      for (let p = 0; p < d.meta.n; ++p) {
        const k = d.prev[p];
        const src = k === 0xffffffff ? d.pos : S.pos;
        const at = k === 0xffffffff ? p : k;
        from[3 * p] = src[3 * at]; from[3 * p + 1] = src[3 * at + 1]; from[3 * p + 2] = src[3 * at + 2];
      }
    }
    for (const key of ['pos', 'radius', 'phi', 'color', 'edges', 'weights', 'a2', 'degree', 'clusters', 'nodes', 'shape', 'labels']) S[key] = d[key];
    Object.assign(S, { meta: d.meta, gen: d.meta.generation, n: d.meta.n, m: d.meta.m });
    S.content = new Map((d.meta.content || []).map((c) => [c.particle, c]));
    // The earlier generation's content textures go with it; prepareContent makes this one's.
    for (const t of S.contentTex.values()) gl.deleteTexture(t.tex);
    S.contentTex = new Map();
    S.levelOffset = [0];
    for (const c of d.meta.hierarchy_levels) S.levelOffset.push(S.levelOffset[S.levelOffset.length - 1] + c);
    S.incident = indexEdges();
    S.children = indexChildren();
    S.transition = from ? { from, start: performance.now(), seconds: 1.0 } : null;
    S.shown = S.pos;
    G.tubeKey = null;
  }
  async function pollGenerations() {
    try {
      const meta = await (await fetch('meta.json')).json();
      if (meta.generation !== S.gen) {
        install(await loadGeneration(meta));
        await prepareContent();
      }
    } catch (e) { /* the server is gone or switched mid-fetch: try again */ }
    setTimeout(pollGenerations, 1000);
  }

  // ---- the frame on the CPU: camera frame, frustum, tiers, edge bundles (spec/render.md) ------
  const NEAR = 1e-3;   // kNear
  function cameraFrame(c) {
    const tan = Math.tan((c.fov * Math.PI / 180) / 2);
    return { right: rotate(c.orientation, [1, 0, 0]), up: rotate(c.orientation, [0, 1, 0]), forward: rotate(c.orientation, [0, 0, -1]),
             tan, focal: (S.height / 2) / tan };
  }
  // R1-RND-022: four side planes through the camera and the image edges, and the near plane.
  function frustum(c, f) {
    const ty = f.tan, tx = f.tan * S.width / S.height;
    const sides = [add(mul(f.forward, tx), f.right), sub(mul(f.forward, tx), f.right),
                   add(mul(f.forward, ty), f.up), sub(mul(f.forward, ty), f.up)];
    const planes = sides.map((s) => { const nn = norm(s); return [nn, -dot(nn, c.position)]; });
    planes.push([f.forward, -dot(f.forward, c.position) - NEAR]);
    return planes;
  }
  // Children of every hierarchy node (nodes of the level below; particles for level 0), from the
  // parents and clusters.u32: offsets into one list per level.
  function indexChildren() {
    const out = [];
    for (let l = 0; l < 4; ++l) {
      const count = S.levelOffset[l + 1] - S.levelOffset[l];
      const offset = new Uint32Array(count + 1);
      const members = l === 0 ? S.n : S.levelOffset[l] - S.levelOffset[l - 1];
      const parentOfMember = (k) => l === 0 ? S.clusters[4 * k] : S.nodes[(S.levelOffset[l - 1] + k) * NODE_FLOATS + 9];
      for (let k = 0; k < members; ++k) ++offset[parentOfMember(k) + 1];
      for (let i = 0; i < count; ++i) offset[i + 1] += offset[i];
      const list = new Uint32Array(offset[count]);
      const fill = offset.slice(0, count);
      for (let k = 0; k < members; ++k) list[fill[parentOfMember(k)]++] = k;
      out.push({ offset, list });
    }
    return out;
  }
  // The particles and far-field node kernels of a frame (R1-RND-020..025, 054): the hierarchy is
  // walked from the top; a node wholly inside the frustum whose members all project at or below
  // t3 - band (so all are T-infinity with weight 1) and whose extent is at most theta = 0.25 kernel
  // widths (or half a pixel) is drawn as one kernel at its centroid with its members' summed focus,
  // as the reference's field evaluates it; otherwise level-0 nodes list their visible particles. Each
  // drawn item: index (particles) or -1 - node (kernels), its depth; with per-particle sizes (0 when
  // not listed) and tier counts.
  function classify(c, f) {
    const pl = frustum(c, f), t = S.meta.tiers, nd = S.nodes;
    const size = new Float64Array(S.n);
    const items = [], depths = [];
    const counts = [0, 0, 0, 0, 0];
    let visible = 0;
    const tau = tauCam(c), tfar = tFar(c, f);
    const pos = S.shown;
    const sphereTest = (x, y, z, r) => {   // -1 outside, 1 wholly inside, 0 across
      let inside = 1;
      for (let k = 0; k < 5; ++k) {
        const [nn, off] = pl[k];
        const dist = nn[0] * x + nn[1] * y + nn[2] * z + off;
        if (dist < -r) return -1;
        if (dist < r) inside = 0;
      }
      return inside;
    };
    const stack = [];
    for (let id = 0; id < S.levelOffset[4] - S.levelOffset[3]; ++id) stack.push([3, id]);
    while (stack.length) {
      const [l, id] = stack.pop();
      const key = S.levelOffset[l] + id, o = key * NODE_FLOATS;
      const x = nd[o], y = nd[o + 1], z = nd[o + 2], extent = nd[o + 3], maxr = nd[o + 4];
      const test = sphereTest(x, y, z, extent + maxr);
      if (test < 0) continue;
      const depth = (x - c.position[0]) * f.forward[0] + (y - c.position[1]) * f.forward[1] + (z - c.position[2]) * f.forward[2];
      const nearest = depth - extent - maxr;
      if (test > 0 && nearest > NEAR && 2 * maxr * f.focal / nearest <= t.t3 - t.band) {
        const sigma = Math.max(Math.sqrt(tau * Math.max(depth - extent, 0) / tfar), 0.5 * Math.max(depth - extent, 0) / f.focal);
        // theta sigma as the reference's field aggregates, or half a pixel: members that close
        // to their centroid fall in one pixel (the viewer's level of detail, R1-VIEW-043).
        if (extent <= Math.max(0.25 * sigma, 0.5 * (depth - extent) / f.focal)) {
          items.push(-1 - key); depths.push(depth);
          const members = nd[o + 17];
          counts[4] += members; visible += members;
          continue;
        }
      }
      const ch = S.children[l];
      if (l > 0) {
        for (let k = ch.offset[id + 1]; k-- > ch.offset[id];) stack.push([l - 1, ch.list[k]]);
        continue;
      }
      for (let k = ch.offset[id]; k < ch.offset[id + 1]; ++k) {
        const p = ch.list[k];
        const px = pos[3 * p], py = pos[3 * p + 1], pz = pos[3 * p + 2], r = S.radius[p];
        if (sphereTest(px, py, pz, r) < 0) continue;
        const d = (px - c.position[0]) * f.forward[0] + (py - c.position[1]) * f.forward[1] + (pz - c.position[2]) * f.forward[2];
        const s = d > r + NEAR ? 2 * r * f.focal / d : 1e300;
        size[p] = s;
        ++visible;
        ++counts[s > t.t0 ? 0 : s > t.t1 ? 1 : s > t.t2 ? 2 : s > t.t3 ? 3 : 4];
        items.push(p); depths.push(d);
      }
    }
    return { size, items, depths, counts, visible };
  }
  // Hierarchy endpoints as integers: particle p is p, node (level, id) is n + levelOffset[level] + id,
  // so their order is R1-RND-064's (level, id) with particles as level -1.
  const NODE_FLOATS = 18;
  const nodeAt = (key) => (key - S.n) * NODE_FLOATS;
  function nodeLevel(key) { let l = 0; while (key - S.n >= S.levelOffset[l + 1]) ++l; return l; }
  function endpointOf(p, s, c, f) {
    if (s > S.meta.tiers.t2) return p;
    for (let l = 0; l < 4; ++l) {
      const key = S.n + S.levelOffset[l] + S.clusters[4 * p + l];
      const o = nodeAt(key), nd = S.nodes;
      const depth = (nd[o] - c.position[0]) * f.forward[0] + (nd[o + 1] - c.position[1]) * f.forward[1] + (nd[o + 2] - c.position[2]) * f.forward[2];
      const size = depth > NEAR ? 2 * (nd[o + 3] + nd[o + 4]) * f.focal / depth : Infinity;
      if (size >= S.meta.tiers.t2 || l === 3) return key;
    }
    return -1;
  }
  function parentOf(key) {
    if (key < S.n) return S.n + S.clusters[4 * key];
    const l = nodeLevel(key);
    return S.n + S.levelOffset[l + 1] + S.nodes[nodeAt(key) + 9];
  }
  function ancestors(key) {
    const chain = [key];
    while (key < S.n || nodeLevel(key) < 3) chain.push(key = parentOf(key));
    return chain;
  }
  function route(a, b) {
    const ca = ancestors(a), cb = ancestors(b);
    let i = 0, j = 0;
    for (i = 0; i < ca.length; ++i) { j = cb.indexOf(ca[i]); if (j >= 0) break; }
    if (i === ca.length) return ca.concat(cb.slice().reverse());
    const out = ca.slice(0, i);
    if (i === 0 || j === 0) out.push(ca[i]);
    for (let k = j - 1; k >= 0; --k) out.push(cb[k]);
    return out;
  }
  const endpointPos = (key) => key < S.n ? [S.shown[3 * key], S.shown[3 * key + 1], S.shown[3 * key + 2]]
                                         : [S.nodes[nodeAt(key)], S.nodes[nodeAt(key) + 1], S.nodes[nodeAt(key) + 2]];
  const endpointRadius = (key) => key < S.n ? S.radius[key] : S.nodes[nodeAt(key) + 5];
  const endpointColor = (key) => key < S.n ? [S.color[3 * key], S.color[3 * key + 1], S.color[3 * key + 2]]
                                           : [S.nodes[nodeAt(key) + 6], S.nodes[nodeAt(key) + 7], S.nodes[nodeAt(key) + 8]];
  // R1-RND-064..066: the edges with an endpoint at T2 or above, routed through the hierarchy,
  // equal segments merged into one tube; per tube a, b, colours, rho, stripes and flow speed.
  function bundle(c, f, size) {
    const t2 = S.meta.tiers.t2, total = S.n + S.levelOffset[4];
    const merged = new Map();
    for (let e = 0; e < S.m; ++e) {
      const p = S.edges[2 * e], q = S.edges[2 * e + 1];
      if (!(size[p] > t2) && !(size[q] > t2)) continue;
      const nodes = route(endpointOf(p, size[p], c, f), endpointOf(q, size[q], c, f));
      for (let k = 0; k + 1 < nodes.length; ++k) {
        let a = nodes[k], b = nodes[k + 1];
        const pa = endpointPos(a), pb = endpointPos(b);
        if (pa[0] === pb[0] && pa[1] === pb[1] && pa[2] === pb[2]) continue;
        let a2 = S.a2[e], deg = S.degree[p];
        if (b < a) { [a, b] = [b, a]; a2 = -a2; deg = S.degree[q]; }
        const key = a * total + b;
        let t = merged.get(key);
        if (!t) merged.set(key, t = { a, b, w: 0, a2: 0, deg: 0 });
        t.w += S.weights[e]; t.a2 += a2; t.deg += deg;
      }
    }
    // An opened particle (T0 with content, R1-RND-130) is entered by its edges at its bounding
    // sphere: a tube ending at it, or at a one-member cluster of it, is cut back by its radius.
    const cut = new Map();
    for (const p of S.contentTex.keys()) {
      if (!(size[p] > S.meta.tiers.t0)) continue;
      cut.set(p, S.radius[p]);
      for (let l = 0; l < 4; ++l) {
        const key = S.n + S.levelOffset[l] + S.clusters[4 * p + l];
        if (S.nodes[nodeAt(key) + 17] === 1) cut.set(key, S.radius[p]);
      }
    }
    const tubes = [];
    for (const t of [...merged.keys()].sort((x, y) => x - y).map((k) => merged.get(k))) {
      let a = endpointPos(t.a), b = endpointPos(t.b);
      const ca = cut.get(t.a) || 0, cb = cut.get(t.b) || 0;
      if (ca > 0 || cb > 0) {
        const l = len(sub(b, a));
        if (!(ca + cb < l)) continue;
        const dir = mul(sub(b, a), 1 / l);
        b = sub(b, mul(dir, cb));
        a = add(a, mul(dir, ca));
      }
      const rho = Math.min(0.1 * S.meta.median_radius * Math.sqrt(t.w), 0.3 * Math.min(endpointRadius(t.a), endpointRadius(t.b)));
      if (!(rho > 0)) continue;
      const pab = t.deg > 0 ? t.w / t.deg : 0;
      const speed = Math.sign(t.a2) * Math.abs(pab);
      const stripes = Math.max(1, Math.round(len(sub(b, a)) / (8 * rho)));
      tubes.push([...a, ...b, ...endpointColor(t.a), ...endpointColor(t.b), rho, stripes, speed]);
    }
    return tubes;
  }

  // ---- WebGL2 ----------------------------------------------------------------------------------
  const canvas = document.getElementById('gl');
  const overlay = document.getElementById('labels');
  const ctx2d = overlay.getContext('2d');
  const gl = canvas.getContext('webgl2', { antialias: false, preserveDrawingBuffer: true });
  // drawn: frames drawn so far; drewLast: whether the last animation frame drew (R1-VIEW-044).
  const G = { drawn: 0, drewLast: false };
  const FAR = 1e6;

  const common = `#version 300 es
precision highp float;
precision highp int;
uniform mat3 uView;     // scene to camera (camera looks along -z)
uniform vec3 uEye;
uniform float uFocal;   // pixels per unit at unit depth
uniform vec2 uViewport;
uniform vec4 uTiers;    // t3, t2, t1, t0 (projected diameters in pixels)
uniform float uBand;    // the T3 / T-infinity handoff band (R1-RND-045)
uniform float uTau;     // camera-to-tau (R-1.0 9.5)
uniform float uTfar;    // the far end of a ray through the scene
uniform float uTime;    // seconds, for the edge flow
vec4 project(vec3 c) { return vec4(c.x * uFocal * 2.0 / uViewport.x, c.y * uFocal * 2.0 / uViewport.y, 0.0, -c.z); }
vec2 pixel(vec3 c) { return c.xy / -c.z * uFocal; }
`;
  // Particles: pass 0 draws T0..T2 as ray-cast shapes (R1-RND-061's headlight); pass 1 the T3
  // EWA Gaussian splats (R1-RND-040..045) and the T-infinity field's kernels, each a column of
  // optical depth kappa sqrt(2 pi) w exp(-d^2 / 2 sigma^2) (R1-RND-051..053), in one stream.
  const particleVs = common + `
layout(location = 0) in vec2 aCorner;
layout(location = 1) in vec3 aCenter;
layout(location = 2) in float aRadius;
layout(location = 3) in vec3 aColor;
layout(location = 4) in float aNphi;
layout(location = 5) in float aShape;
uniform int uPass;
uniform int uField;     // 1: draw the T-infinity kernels
out vec3 vCenter; out vec3 vPoint; out vec3 vColor; out float vRadius; out vec3 vConic; out float vWeight;
out vec3 vConicF; out float vWeightF;
flat out int vShape;
// EWA (R1-RND-041): the screen conic of a Gaussian of width sigma at camera-space c, plus a
// low-pass of extra px^2; h is the half extent in scene units that holds reach sigmas.
vec3 screenConic(vec3 c, float sigma, float extra, float reach, out float h) {
  float d = -c.z, fz = uFocal / d, xs = c.x / d, ys = c.y / d;
  float s2 = sigma * sigma * fz * fz;
  float c00 = s2 * (1.0 + xs * xs) + extra, c11 = s2 * (1.0 + ys * ys) + extra, c01 = s2 * xs * ys;
  float det = c00 * c11 - c01 * c01;
  h = reach * sqrt(max(c00, c11) + abs(c01)) / fz;
  return vec3(c11, -c01, c00) / det;
}
void main() {
  vec3 c = uView * (aCenter - uEye);
  float d = -c.z;
  float s = d > aRadius + 1e-3 ? 2.0 * aRadius * uFocal / d : 1e30;
  float winf = clamp((uTiers.x + uBand - s) / (2.0 * uBand), 0.0, 1.0);
  // Pass 0: T0..T2 shapes. Pass 1: everything translucent in one far-to-near stream, so that a
  // splat inside a cloud of field kernels is covered by the kernels in front of it as the
  // reference's ray march covers it (R1-RND-070): T3 splats and T-infinity kernels, a particle in
  // the handoff band being both.
  bool draw = d > 1e-3 && (uPass == 0 ? s > uTiers.y : s <= uTiers.y);
  if (uPass == 0 && d <= aRadius) draw = false;
  int shape = int(aShape + 0.5);
  bool opened = shape >= 16;
  if (uPass == 0 && opened && s > uTiers.w) draw = false;   // the content pass draws it
  vWeight = s > uTiers.x - uBand ? 0.9 * (1.0 - winf) : 0.0;
  vWeightF = uField == 1 ? 0.25 * 2.5066283 * aNphi * winf : 0.0;
  if (uPass == 1 && !(vWeight > 0.0 || vWeightF > 0.0)) draw = false;
  if (!draw) { gl_Position = vec4(2.0, 2.0, 2.0, 1.0); return; }
  vCenter = c; vColor = aColor; vRadius = aRadius; vShape = opened ? shape - 16 : shape;
  float L = length(c);
  vec3 fw = c / L;
  vec3 side = abs(fw.y) < 0.99 ? vec3(0.0, 1.0, 0.0) : vec3(1.0, 0.0, 0.0);
  vec3 right = normalize(cross(fw, side));
  vec3 up = cross(right, fw);
  float h = 0.0;
  if (uPass == 0) {
    h = aRadius * L / sqrt(L * L - aRadius * aRadius) * 1.02;   // the tangent cone's section
  } else {
    // Splats reach alpha 1/255 (R1-RND-043) within 3.2 sigma; the field's kernels count to 4 sigma
    // (R1-RND-054 cuts at 5; spec/viewer.md says why 4 here), where many faint tails add up.
    float hs = 0.0, hf = 0.0;
    if (vWeight > 0.0) vConic = screenConic(c, 0.5 * aRadius, 0.3, 3.2, hs);
    if (vWeightF > 0.0) vConicF = screenConic(c, max(sqrt(uTau * d / uTfar), 0.5 * d / uFocal), 0.0, 4.0, hf);
    h = max(hs, hf);
  }
  vPoint = c + (right * aCorner.x + up * aCorner.y) * h;
  gl_Position = project(vPoint);
}`;
  // The shapes of R1-RND-031, axis-aligned in scene coordinates inside the bounding sphere of
  // radius r: ray o + t d relative to the centre (scene axes), nearest hit in front, outward normal.
  const shapesGlsl = `
const float kR3 = 0.57735026919;   // 1 / sqrt 3
bool slabs(vec3 o, vec3 d, vec3 nrm[8], float off[8], int count, out float t, out vec3 n) {
  // Kay-Kajiya: entry = the largest t over faces the ray enters, exit = the smallest over the others.
  float t0 = -1e30, t1 = 1e30;
  vec3 n0 = vec3(0.0);
  for (int k = 0; k < 8; ++k) {
    if (k >= count) break;
    float dn = dot(nrm[k], d), on = dot(nrm[k], o) - off[k];
    if (abs(dn) < 1e-12) { if (on > 0.0) return false; continue; }
    float tk = -on / dn;
    if (dn < 0.0) { if (tk > t0) { t0 = tk; n0 = nrm[k]; } } else { t1 = min(t1, tk); }
  }
  if (t0 > t1 || t0 <= 0.0) return false;
  t = t0; n = n0;
  return true;
}
bool hitShape(int shape, vec3 o, vec3 d, float r, out float t, out vec3 n) {
  vec3 nrm[8]; float off[8];
  if (shape == 2) {          // tetrahedron
    nrm[0] = vec3(-1.0, 1.0, 1.0) * kR3; nrm[1] = vec3(1.0, -1.0, 1.0) * kR3;
    nrm[2] = vec3(1.0, 1.0, -1.0) * kR3; nrm[3] = vec3(-1.0, -1.0, -1.0) * kR3;
    for (int k = 0; k < 4; ++k) off[k] = r / 3.0;
    return slabs(o, d, nrm, off, 4, t, n);
  }
  if (shape == 3) {          // cube
    nrm[0] = vec3(1.0, 0.0, 0.0); nrm[1] = vec3(-1.0, 0.0, 0.0); nrm[2] = vec3(0.0, 1.0, 0.0);
    nrm[3] = vec3(0.0, -1.0, 0.0); nrm[4] = vec3(0.0, 0.0, 1.0); nrm[5] = vec3(0.0, 0.0, -1.0);
    for (int k = 0; k < 6; ++k) off[k] = r * kR3;
    return slabs(o, d, nrm, off, 6, t, n);
  }
  if (shape == 4) {          // octahedron
    for (int k = 0; k < 8; ++k) {
      nrm[k] = vec3((k & 1) == 0 ? 1.0 : -1.0, (k & 2) == 0 ? 1.0 : -1.0, (k & 4) == 0 ? 1.0 : -1.0) * kR3;
      off[k] = r * kR3;
    }
    return slabs(o, d, nrm, off, 8, t, n);
  }
  if (shape == 5) {          // cylinder about z, radius and half height r / sqrt 2
    float rc = r * 0.70710678, h = rc;
    float a = dot(d.xy, d.xy), b = dot(o.xy, d.xy), c = dot(o.xy, o.xy) - rc * rc;
    float tw0 = -1e30, tw1 = 1e30;
    if (a > 1e-12) {
      float disc = b * b - a * c;
      if (disc < 0.0) return false;
      float sq = sqrt(disc);
      tw0 = (-b - sq) / a; tw1 = (-b + sq) / a;
    } else if (c > 0.0) return false;
    float tz0 = -1e30, tz1 = 1e30;
    if (abs(d.z) > 1e-12) { tz0 = (-h - o.z) / d.z; tz1 = (h - o.z) / d.z; if (tz0 > tz1) { float s = tz0; tz0 = tz1; tz1 = s; } }
    else if (abs(o.z) > h) return false;
    float t0 = max(tw0, tz0), t1 = min(tw1, tz1);
    if (t0 > t1 || t0 <= 0.0) return false;
    t = t0;
    vec3 p = o + d * t;
    n = tw0 >= tz0 ? normalize(vec3(p.xy, 0.0)) : vec3(0.0, 0.0, sign(p.z));
    return true;
  }
  float b = dot(o, d), c = dot(o, o) - r * r, disc = b * b - c;
  if (disc < 0.0) return false;
  float t0 = -b - sqrt(disc);
  if (shape == 1) {          // torus about z: major 0.65 r, minor 0.35 r; sphere-traced from the entry
    float R = 0.65 * r, A = 0.35 * r, tmax = -b + sqrt(disc);
    t = max(t0, 0.0);
    for (int i = 0; i < 96; ++i) {
      vec3 p = o + d * t;
      float f = length(vec2(length(p.xy) - R, p.z)) - A;
      if (f < 1e-4 * r) {
        vec2 q = length(p.xy) > 0.0 ? normalize(p.xy) * R : vec2(R, 0.0);
        n = normalize(p - vec3(q, 0.0));
        return t > 0.0;
      }
      t += f;
      if (t > tmax) return false;
    }
    return false;
  }
  if (t0 <= 0.0) return false;
  t = t0; n = (o + d * t) / r;
  return true;
}`;
  const particleFs = common + shapesGlsl + `
in vec3 vCenter; in vec3 vPoint; in vec3 vColor; in float vRadius; in vec3 vConic; in float vWeight;
in vec3 vConicF; in float vWeightF;
flat in int vShape;
uniform int uPass;
out vec4 outColor;
float conicQ(vec3 k, vec2 dd) { return k.x * dd.x * dd.x + 2.0 * k.y * dd.x * dd.y + k.z * dd.y * dd.y; }
void main() {
  vec3 dir = normalize(vPoint);
  if (uPass == 0) {
    // In scene axes (the shapes are axis-aligned there): the rows of uView are the camera axes.
    mat3 toScene = transpose(uView);
    vec3 d = toScene * dir, o = toScene * (-vCenter);
    float t; vec3 n;
    if (!hitShape(vShape, o, d, vRadius, t, n)) discard;
    outColor = vec4(vColor * (0.25 + 0.75 * max(0.0, -dot(n, d))), 1.0);   // R1-RND-061's headlight
    gl_FragDepth = -(dir * t).z / ${FAR.toFixed(1)};
    return;
  }
  vec2 dd = pixel(vPoint) - pixel(vCenter);
  float as = vWeight > 0.0 ? min(0.99, vWeight * exp(-0.5 * conicQ(vConic, dd))) : 0.0;
  if (as < 1.0 / 255.0) as = 0.0;
  float af = vWeightF > 0.0 ? 1.0 - exp(-vWeightF * exp(-0.5 * conicQ(vConicF, dd))) : 0.0;
  // The splat over the kernel: one colour, so their alphas combine.
  float a = 1.0 - (1.0 - as) * (1.0 - af);
  if (!(a > 0.0)) discard;
  outColor = vec4(vColor * a, a);
  gl_FragDepth = -vCenter.z / ${FAR.toFixed(1)};
}`;
  // T0 content (R1-RND-130..135, R1-VIEW-073): a textured panel or page in scene coordinates,
  // unlit, into the opaque layer. Textures are display sRGB stored as SRGB8_ALPHA8, so they are
  // sampled (bilinearly) in linear light; an image's transparent pixels show linear 0.05 grey.
  const contentVs = common + `
layout(location = 0) in vec3 aPos;
layout(location = 1) in vec2 aUv;
out vec2 vUv; out float vDepth;
void main() {
  vec3 c = uView * (aPos - uEye);
  vUv = aUv; vDepth = -c.z;
  gl_Position = project(c);
}`;
  const contentFs = common + `
in vec2 vUv; in float vDepth;
uniform sampler2D uTex;
out vec4 outColor;
void main() {
  vec4 t = texture(uTex, vUv);
  outColor = vec4(t.rgb * t.a + vec3(0.05) * (1.0 - t.a), 1.0);
  gl_FragDepth = vDepth / ${FAR.toFixed(1)};
}`;
  // Edge tubes (R1-RND-065, 066): a quad along a..b as wide as the tube, shaded as a cylinder under
  // the headlight, with the flow strip.
  const tubeVs = common + `
layout(location = 0) in vec2 aCorner;     // x: 0 at a, 1 at b; y: -1 .. 1 across
layout(location = 1) in vec3 aA;
layout(location = 2) in vec3 aB;
layout(location = 3) in vec3 aColorA;
layout(location = 4) in vec3 aColorB;
layout(location = 5) in vec3 aTube;       // rho, stripes, flow speed
out vec3 vColor; out float vAcross; out float vDepth; out float vU; out vec2 vStrip;
void main() {
  vec3 a = uView * (aA - uEye), b = uView * (aB - uEye);
  float near = 2.0 * aTube.x + 1e-3;
  // Clip the segment to depth >= 2 rho + near (R1-RND-065).
  float da = -a.z, db = -b.z;
  if (da < near && db < near) { gl_Position = vec4(2.0, 2.0, 2.0, 1.0); return; }
  float u0 = 0.0, u1 = 1.0;
  if (da < near) u0 = (near - da) / (db - da);
  if (db < near) u1 = (da - near) / (da - db);
  float u = mix(u0, u1, aCorner.x);
  vec3 p = mix(a, b, u);
  vec3 axis = normalize(b - a);
  vec3 across = cross(axis, normalize(p));
  if (length(across) < 1e-6) across = vec3(1.0, 0.0, 0.0);
  p += normalize(across) * aTube.x * aCorner.y;
  vColor = mix(aColorA, aColorB, u); vAcross = aCorner.y; vDepth = -p.z; vU = u; vStrip = aTube.yz;
  gl_Position = project(p);
}`;
  const tubeFs = common + `
in vec3 vColor; in float vAcross; in float vDepth; in float vU; in vec2 vStrip;
out vec4 outColor;
void main() {
  float phase = vStrip.x * vU - vStrip.y * uTime;
  float strip = 0.55 + 0.45 * 0.5 * (1.0 + cos(6.2831853 * (phase - floor(phase))));
  float facing = sqrt(max(0.0, 1.0 - vAcross * vAcross));
  outColor = vec4(vColor * 0.6 * strip * (0.25 + 0.75 * facing), 1.0);
  gl_FragDepth = vDepth / ${FAR.toFixed(1)};
}`;
  const blitVs = `#version 300 es
const vec2 v[3] = vec2[3](vec2(-1.0, -1.0), vec2(3.0, -1.0), vec2(-1.0, 3.0));
void main() { gl_Position = vec4(v[gl_VertexID], 0.0, 1.0); }`;
  const blitFs = `#version 300 es
precision highp float;
uniform sampler2D uScene; out vec4 outColor;
vec3 oetf(vec3 c) {   // linear light to display sRGB
  c = clamp(c, 0.0, 1.0);
  return mix(c * 12.92, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, step(vec3(0.0031308), c));
}
void main() { outColor = vec4(oetf(texelFetch(uScene, ivec2(gl_FragCoord.xy), 0).rgb), 1.0); }`;

  function program(vs, fs) {
    const compile = (type, src) => {
      const sh = gl.createShader(type);
      gl.shaderSource(sh, src);
      gl.compileShader(sh);
      if (!gl.getShaderParameter(sh, gl.COMPILE_STATUS)) throw new Error('shader: ' + gl.getShaderInfoLog(sh));
      return sh;
    };
    const p = gl.createProgram();
    gl.attachShader(p, compile(gl.VERTEX_SHADER, vs));
    gl.attachShader(p, compile(gl.FRAGMENT_SHADER, fs));
    gl.linkProgram(p);
    if (!gl.getProgramParameter(p, gl.LINK_STATUS)) throw new Error('program: ' + gl.getProgramInfoLog(p));
    return p;
  }
  function gpuInit() {
    if (!gl) throw new Error('this browser has no WebGL2');
    G.float = !!gl.getExtension('EXT_color_buffer_float');
    G.particle = program(particleVs, particleFs);
    G.tube = program(tubeVs, tubeFs);
    G.blit = program(blitVs, blitFs);
    G.content = program(contentVs, contentFs);
    G.contentBuf = gl.createBuffer();
    G.contentVao = gl.createVertexArray();
    gl.bindVertexArray(G.contentVao);
    gl.bindBuffer(gl.ARRAY_BUFFER, G.contentBuf);
    gl.enableVertexAttribArray(0);
    gl.vertexAttribPointer(0, 3, gl.FLOAT, false, 20, 0);
    gl.enableVertexAttribArray(1);
    gl.vertexAttribPointer(1, 2, gl.FLOAT, false, 20, 12);
    gl.bindVertexArray(null);
    G.quad = gl.createBuffer();
    gl.bindBuffer(gl.ARRAY_BUFFER, G.quad);
    gl.bufferData(gl.ARRAY_BUFFER, new Float32Array([-1, -1, 1, -1, -1, 1, 1, 1]), gl.STATIC_DRAW);
    G.strip = gl.createBuffer();
    gl.bindBuffer(gl.ARRAY_BUFFER, G.strip);
    gl.bufferData(gl.ARRAY_BUFFER, new Float32Array([0, -1, 1, -1, 0, 1, 1, 1]), gl.STATIC_DRAW);
    G.instances = gl.createBuffer();
    G.tubes = gl.createBuffer();
    G.vao = gl.createVertexArray();
    G.tubeVao = gl.createVertexArray();
    // A vertex array: the corner buffer per vertex, then the instance buffer's float attributes
    // (sizes in floats, packed in order) per instance.
    const instanced = (vao, corners, instances, sizes) => {
      gl.bindVertexArray(vao);
      gl.bindBuffer(gl.ARRAY_BUFFER, corners);
      gl.enableVertexAttribArray(0);
      gl.vertexAttribPointer(0, 2, gl.FLOAT, false, 0, 0);
      gl.bindBuffer(gl.ARRAY_BUFFER, instances);
      const stride = 4 * sizes.reduce((a, b) => a + b, 0);
      let offset = 0;
      sizes.forEach((size, i) => {
        gl.enableVertexAttribArray(i + 1);
        gl.vertexAttribPointer(i + 1, size, gl.FLOAT, false, stride, offset);
        gl.vertexAttribDivisor(i + 1, 1);
        offset += 4 * size;
      });
    };
    instanced(G.vao, G.quad, G.instances, [3, 1, 3, 1, 1]);     // centre, radius, colour, n phi, shape
    instanced(G.tubeVao, G.strip, G.tubes, [3, 3, 3, 3, 3]);    // a, b, colour a, colour b, (rho, stripes, speed)
    gl.bindVertexArray(null);
  }
  // Instances (centre, radius, linear colour, n phi, shape as float32), far to near so that the
  // translucent passes composite in depth order (R1-RND-043; ties by the lower index).
  const SORT_LIMIT = 300000;
  function uploadInstances(cls) {
    const count = cls.items.length;
    const order = new Uint32Array(count);
    for (let i = 0; i < count; ++i) order[i] = i;
    const key = (i) => (cls.items[i] >= 0 ? cls.items[i] : S.n - 1 - cls.items[i]);   // particles, then nodes
    if (count <= SORT_LIMIT) order.sort((a, b) => cls.depths[b] - cls.depths[a] || key(a) - key(b));
    const F = 9, inst = new Float32Array(count * F), pos = S.shown, nd = S.nodes;
    for (let i = 0; i < count; ++i) {
      const item = cls.items[order[i]], o = F * i;
      if (item >= 0) {
        inst[o] = pos[3 * item]; inst[o + 1] = pos[3 * item + 1]; inst[o + 2] = pos[3 * item + 2];
        inst[o + 3] = S.radius[item];
        inst[o + 4] = S.color[3 * item]; inst[o + 5] = S.color[3 * item + 1]; inst[o + 6] = S.color[3 * item + 2];
        inst[o + 7] = S.n * S.phi[item];
        // +16: the particle has T0 content, which replaces its shape at T0 (R1-RND-130).
        inst[o + 8] = S.shape[item] + (S.contentTex.has(item) ? 16 : 0);
      } else {
        // A node kernel: radius 0 puts it in the field pass with weight 1 (R1-RND-045).
        const b = (-1 - item) * NODE_FLOATS;
        inst[o] = nd[b]; inst[o + 1] = nd[b + 1]; inst[o + 2] = nd[b + 2];
        inst[o + 3] = 0;
        inst[o + 4] = nd[b + 6]; inst[o + 5] = nd[b + 7]; inst[o + 6] = nd[b + 8];
        inst[o + 7] = S.n * nd[b + 16];
        inst[o + 8] = 0;
      }
    }
    gl.bindBuffer(gl.ARRAY_BUFFER, G.instances);
    gl.bufferData(gl.ARRAY_BUFFER, inst, gl.DYNAMIC_DRAW);
    G.instanceCount = count;
  }
  function uploadTubes(tubes) {
    const data = new Float32Array(tubes.length * 15);
    tubes.forEach((t, i) => data.set(t, 15 * i));
    gl.bindBuffer(gl.ARRAY_BUFFER, G.tubes);
    gl.bufferData(gl.ARRAY_BUFFER, data, gl.DYNAMIC_DRAW);
    G.tubeCount = tubes.length;
  }
  function ensureTarget() {
    if (G.fbW === S.width && G.fbH === S.height) return;
    G.fbW = S.width; G.fbH = S.height;
    if (G.fb) { gl.deleteFramebuffer(G.fb); gl.deleteTexture(G.tex); gl.deleteRenderbuffer(G.depth); }
    G.tex = gl.createTexture();
    gl.bindTexture(gl.TEXTURE_2D, G.tex);
    gl.texStorage2D(gl.TEXTURE_2D, 1, G.float ? gl.RGBA16F : gl.SRGB8_ALPHA8, S.width, S.height);
    G.depth = gl.createRenderbuffer();
    gl.bindRenderbuffer(gl.RENDERBUFFER, G.depth);
    gl.renderbufferStorage(gl.RENDERBUFFER, gl.DEPTH_COMPONENT24, S.width, S.height);
    G.fb = gl.createFramebuffer();
    gl.bindFramebuffer(gl.FRAMEBUFFER, G.fb);
    gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0, gl.TEXTURE_2D, G.tex, 0);
    gl.framebufferRenderbuffer(gl.FRAMEBUFFER, gl.DEPTH_ATTACHMENT, gl.RENDERBUFFER, G.depth);
    gl.bindFramebuffer(gl.FRAMEBUFFER, null);
  }
  function viewMatrix(q) {
    // The scene-to-camera rotation: rows are the camera axes; a column-major mat3 of its transpose.
    const x = rotate(q, [1, 0, 0]), y = rotate(q, [0, 1, 0]), z = rotate(q, [0, 0, 1]);
    return new Float32Array([x[0], y[0], z[0], x[1], y[1], z[1], x[2], y[2], z[2]]);
  }
  // R1-RND-051, 057: the farthest corner of the top-level boxes, grown by 5 kernel widths there.
  function tFar(c, f) {
    let far = 0;
    for (let id = S.levelOffset[3]; id < S.levelOffset[4]; ++id) {
      const o = id * NODE_FLOATS;
      for (let k = 0; k < 8; ++k) {
        const corner = [S.nodes[o + ((k & 1) ? 13 : 10)], S.nodes[o + ((k & 2) ? 14 : 11)], S.nodes[o + ((k & 4) ? 15 : 12)]];
        far = Math.max(far, len(sub(corner, c.position)));
      }
    }
    far = Math.max(far, 1);
    return far + 5 * Math.max(Math.sqrt(tauCam(c)), 0.5 * far / f.focal + 1e-9);
  }
  function setUniforms(p, c, f, tfar) {
    gl.useProgram(p);
    const u = (name) => gl.getUniformLocation(p, name);
    gl.uniformMatrix3fv(u('uView'), false, viewMatrix(c.orientation));
    gl.uniform3f(u('uEye'), c.position[0], c.position[1], c.position[2]);
    gl.uniform1f(u('uFocal'), f.focal);
    gl.uniform2f(u('uViewport'), S.width, S.height);
    const t = S.meta.tiers;
    gl.uniform4f(u('uTiers'), t.t3, t.t2, t.t1, t.t0);
    gl.uniform1f(u('uBand'), t.band);
    gl.uniform1f(u('uTau'), tauCam(c));
    gl.uniform1f(u('uTfar'), tfar);
    gl.uniform1f(u('uTime'), S.time);
  }
  function draw(c, f) {
    ensureTarget();
    const tfar = tFar(c, f);   // once per frame, for both programs
    gl.bindFramebuffer(gl.FRAMEBUFFER, G.fb);
    gl.viewport(0, 0, S.width, S.height);
    const bg = S.meta.background;
    gl.clearColor(bg[0], bg[1], bg[2], 1);
    gl.clearDepth(1);
    gl.enable(gl.DEPTH_TEST);
    gl.depthFunc(gl.LEQUAL);
    gl.depthMask(true);
    gl.disable(gl.BLEND);
    gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
    if (G.tubeCount > 0) {
      setUniforms(G.tube, c, f, tfar);
      gl.bindVertexArray(G.tubeVao);
      gl.drawArraysInstanced(gl.TRIANGLE_STRIP, 0, 4, G.tubeCount);
    }
    setUniforms(G.particle, c, f, tfar);
    gl.bindVertexArray(G.vao);
    const pass = gl.getUniformLocation(G.particle, 'uPass');
    gl.uniform1i(pass, 0);
    gl.drawArraysInstanced(gl.TRIANGLE_STRIP, 0, 4, G.instanceCount);
    drawContent(c, f);
    // Splats and field kernels in one stream: premultiplied "over", far to near, depth-tested
    // against the opaque layer (R1-RND-070).
    gl.enable(gl.BLEND);
    gl.blendFunc(gl.ONE, gl.ONE_MINUS_SRC_ALPHA);
    gl.depthMask(false);
    gl.uniform1i(gl.getUniformLocation(G.particle, 'uField'), S.showField ? 1 : 0);
    gl.uniform1i(pass, 1);
    gl.drawArraysInstanced(gl.TRIANGLE_STRIP, 0, 4, G.instanceCount);
    gl.disable(gl.BLEND);
    gl.depthMask(true);
    gl.bindVertexArray(null);
    gl.bindFramebuffer(gl.FRAMEBUFFER, null);
    gl.disable(gl.DEPTH_TEST);
    gl.useProgram(G.blit);
    gl.activeTexture(gl.TEXTURE0);
    gl.bindTexture(gl.TEXTURE_2D, G.tex);
    gl.uniform1i(gl.getUniformLocation(G.blit, 'uScene'), 0);
    gl.drawArrays(gl.TRIANGLES, 0, 3);
  }

  // ---- T0 content in the frame (R1-RND-130..135, R1-VIEW-073) -----------------------------------
  const TEXT_RADIUS = 0.7, TEXT_HALF_ANGLE = Math.PI / 3, TEXT_WIDTH = 1024, TEXT_SIZE = 44, TEXT_LINE = 56, TEXT_MARGIN = 48;
  const CARD_W = 1024, CARD_H = 640;
  const srgb = (v) => Math.round(255 * (v <= 0.0031308 ? 12.92 * v : 1.055 * Math.pow(v, 1 / 2.4) - 0.055));
  const css = (rgb) => `rgb(${rgb.map(srgb).join(',')})`;
  const fileName = (p) => p.split('/').pop();
  function paperCanvas(w, h, background) {
    const cv = document.createElement('canvas');
    cv.width = w; cv.height = h;
    const g = cv.getContext('2d');
    g.fillStyle = css(background);
    g.fillRect(0, 0, w, h);
    return [cv, g];
  }
  // The longest prefix of s (by code points) that fits within width, else at least one.
  function fitPrefix(g, s, width) {
    const cps = [...s];
    let lo = 0, hi = cps.length;
    while (hi - lo > 1) { const mid = (lo + hi) >> 1; if (g.measureText(cps.slice(0, mid).join('')).width <= width) lo = mid; else hi = mid; }
    return Math.max(lo, 1);
  }
  function cardCanvas(background, title, subtitle) {
    const [cv, g] = paperCanvas(CARD_W, CARD_H, background);
    g.fillStyle = css([0.9, 0.9, 0.9]);
    g.textAlign = 'center';
    g.textBaseline = 'alphabetic';
    g.font = '110px "DejaVu Sans", sans-serif';
    g.fillText(title, CARD_W / 2, CARD_H / 2, CARD_W - 40);
    g.font = '34px "DejaVu Sans", sans-serif';
    g.fillText(subtitle, CARD_W / 2, CARD_H / 2 + 90, CARD_W - 40);
    return cv;
  }
  // R1-RND-133's page: 44 px type on a 56 px pitch, 48 px margins, greedy breaks between words.
  function pageCanvas(text) {
    const arc = 2 * TEXT_RADIUS * TEXT_HALF_ANGLE, high = 2 * Math.sqrt(1 - TEXT_RADIUS * TEXT_RADIUS);
    const h = Math.round(TEXT_WIDTH * high / arc), width = TEXT_WIDTH - 2 * TEXT_MARGIN;
    const [cv, g] = paperCanvas(TEXT_WIDTH, h, [0.80, 0.78, 0.72]);
    g.font = `${TEXT_SIZE}px "DejaVu Sans", sans-serif`;
    g.fillStyle = css([0.015, 0.015, 0.015]);
    g.textBaseline = 'alphabetic';
    const maxLines = Math.max(1, Math.floor((h - 2 * TEXT_MARGIN) / TEXT_LINE));
    const lines = [];
    const clean = text.replace(/[\u0000-\u0009\u000b-\u001f\u007f]/g, ' ');
    for (const para of clean.split('\n')) {
      let line = '';
      for (let word of para.split(' ').filter((w) => w.length)) {
        const trial = line ? line + ' ' + word : word;
        if (g.measureText(trial).width <= width) { line = trial; continue; }
        if (line) lines.push(line);
        line = '';
        while (g.measureText(word).width > width) {
          const n = fitPrefix(g, word, width), cps = [...word];
          lines.push(cps.slice(0, n).join(''));
          word = cps.slice(n).join('');
        }
        line = word;
      }
      lines.push(line);
    }
    if (lines.length > maxLines) {
      lines.length = maxLines;
      const last = lines[maxLines - 1] + ' \u2026';
      lines[maxLines - 1] = [...last].slice(0, fitPrefix(g, last, width)).join('');
    }
    lines.forEach((l, k) => g.fillText(l, TEXT_MARGIN, TEXT_MARGIN + TEXT_SIZE + k * TEXT_LINE));
    return cv;
  }
  function texture(source) {
    const tex = gl.createTexture();
    gl.bindTexture(gl.TEXTURE_2D, tex);
    gl.pixelStorei(gl.UNPACK_COLORSPACE_CONVERSION_WEBGL, gl.NONE);
    gl.pixelStorei(gl.UNPACK_PREMULTIPLY_ALPHA_WEBGL, false);
    gl.texImage2D(gl.TEXTURE_2D, 0, gl.SRGB8_ALPHA8, gl.RGBA, gl.UNSIGNED_BYTE, source);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, gl.LINEAR);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MAG_FILTER, gl.LINEAR);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_WRAP_S, gl.CLAMP_TO_EDGE);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_WRAP_T, gl.CLAMP_TO_EDGE);
    return { tex, w: source.width, h: source.height };
  }
  // Every content entry of the generation as a texture, the way the reference prepares it
  // (R1-RND-132..134): images, text pages, and cards for the rest.
  async function prepareContent() {
    const gen = S.gen, out = new Map();
    const CARDS = { other: [0.06, 0.09, 0.16], missing: [0.30, 0.02, 0.02], unreadable: [0.30, 0.13, 0.01], refused: [0.20, 0.02, 0.22] };
    for (const [p, c] of S.content) {
      let t = null;
      try {
        if (c.status === 'ok' && c.kind === 'image') {
          const img = new Image();
          img.src = c.url;
          await img.decode();
          t = texture(img);
        } else if (c.status === 'ok' && c.kind === 'text') {
          const r = await fetch(c.url);
          if (!r.ok) throw new Error(`HTTP ${r.status}`);
          t = { ...texture(pageCanvas(await r.text())), page: true };
        }
      } catch (e) {
        t = texture(cardCanvas(CARDS.unreadable, 'unreadable', `${fileName(c.source)}: the browser cannot show it`));
      }
      if (!t) {
        t = c.status === 'ok' ? texture(cardCanvas(CARDS.other, c.type, fileName(c.source)))
          : texture(cardCanvas(CARDS[c.status] || CARDS.unreadable, c.status,
                               c.status === 'refused' ? `${c.source}: ${c.reason}` : c.status === 'missing' ? fileName(c.source)
                                 : `${fileName(c.source)}: ${c.reason}`));
      }
      out.set(p, t);
    }
    if (S.gen !== gen) {   // a newer generation arrived meanwhile: these textures are not its
      for (const t of out.values()) gl.deleteTexture(t.tex);
      return;
    }
    S.contentTex = out;
    G.tubeKey = null;   // the instances carry the content flag
  }
  // The panels and pages of the visible T0 particles with content (R1-RND-131, 133).
  function drawContent(c, f) {
    S.contentDrawn = 0;
    if (!S.contentTex.size || !G.cls) return;
    const t0 = S.meta.tiers.t0, verts = [], draws = [];
    for (const [p, t] of S.contentTex) {
      if (!(G.cls.size[p] > t0)) continue;
      const X = [S.shown[3 * p], S.shown[3 * p + 1], S.shown[3 * p + 2]], r = S.radius[p];
      const toEye = sub(c.position, X);
      const n = len(toEye) > 0 ? mul(toEye, 1 / len(toEye)) : mul(f.forward, -1);
      let ex = sub(f.right, mul(n, dot(f.right, n)));
      ex = len(ex) > 1e-12 ? mul(ex, 1 / len(ex)) : norm(cross(f.up, n));
      const ey = cross(n, ex);
      const first = verts.length / 5;
      const put = (q, u, v) => verts.push(q[0], q[1], q[2], u, v);
      if (!t.page) {
        const a = t.w / t.h, hh = r / Math.sqrt(1 + a * a), hw = a * hh;
        const at = (sx, sy) => add(X, add(mul(ex, sx * hw), mul(ey, sy * hh)));
        put(at(-1, 1), 0, 0); put(at(-1, -1), 0, 1); put(at(1, 1), 1, 0); put(at(1, -1), 1, 1);
      } else {
        const R = TEXT_RADIUS * r, hh = r * Math.sqrt(1 - TEXT_RADIUS * TEXT_RADIUS), axis = add(X, mul(n, R)), cols = 48;
        for (let i = 0; i <= cols; ++i) {
          const th = -TEXT_HALF_ANGLE + 2 * TEXT_HALF_ANGLE * i / cols, u = i / cols;
          const q = add(axis, add(mul(n, -R * Math.cos(th)), mul(ex, R * Math.sin(th))));
          put(add(q, mul(ey, hh)), u, 0); put(add(q, mul(ey, -hh)), u, 1);
        }
      }
      draws.push([t.tex, first, verts.length / 5 - first]);
    }
    S.contentDrawn = draws.length;
    if (!draws.length) return;
    setUniforms(G.content, c, f, 1);
    gl.bindVertexArray(G.contentVao);
    gl.bindBuffer(gl.ARRAY_BUFFER, G.contentBuf);
    gl.bufferData(gl.ARRAY_BUFFER, new Float32Array(verts), gl.DYNAMIC_DRAW);
    gl.activeTexture(gl.TEXTURE0);
    gl.uniform1i(gl.getUniformLocation(G.content, 'uTex'), 0);
    for (const [tex, first, count] of draws) {
      gl.bindTexture(gl.TEXTURE_2D, tex);
      gl.drawArrays(gl.TRIANGLE_STRIP, first, count);
    }
    gl.useProgram(G.particle);
    gl.bindVertexArray(G.vao);
  }

  // ---- labels (R1-RND-067) --------------------------------------------------------------------
  function drawLabels(c, f, cls) {
    ctx2d.clearRect(0, 0, overlay.width, overlay.height);
    if (!S.showLabels) return 0;
    const t1 = S.meta.tiers.t1, t2 = S.meta.tiers.t2, labelled = [], discs = [];
    const project = (p) => {
      const rel = sub(P(p), c.position), d = dot(rel, f.forward);
      return { p, d, px: S.width / 2 + dot(rel, f.right) / d * f.focal, py: S.height / 2 - dot(rel, f.up) / d * f.focal,
               rp: S.radius[p] * f.focal / d };
    };
    for (let p = 0; p < S.n; ++p) {
      if (!(cls.size[p] > t2)) continue;
      const q = project(p);
      if (!(q.d > 1e-3)) continue;
      discs.push(q);
      if (cls.size[p] > t1) labelled.push(q);
    }
    // A label shows only where its particle is the nearest shape at its centre (R1-RND-067):
    // the discs of the shapes, bucketed in 64-pixel cells, stand for their surfaces.
    const cell = 64, gw = Math.ceil(S.width / cell), gh = Math.ceil(S.height / cell), grid = new Map();
    for (const q of discs) {
      const x0 = Math.max(0, Math.floor((q.px - q.rp) / cell)), x1 = Math.min(gw - 1, Math.floor((q.px + q.rp) / cell));
      const y0 = Math.max(0, Math.floor((q.py - q.rp) / cell)), y1 = Math.min(gh - 1, Math.floor((q.py + q.rp) / cell));
      for (let y = y0; y <= y1; ++y) for (let x = x0; x <= x1; ++x) {
        const k = y * gw + x;
        if (!grid.has(k)) grid.set(k, []);
        grid.get(k).push(q);
      }
    }
    const hidden = (l) => {
      const gx = Math.floor(l.px / cell), gy = Math.floor(l.py / cell);
      if (gx < 0 || gy < 0 || gx >= gw || gy >= gh) return true;
      for (const q of grid.get(gy * gw + gx) || [])
        if ((q.d < l.d || (q.d === l.d && q.p < l.p)) && Math.hypot(q.px - l.px, q.py - l.py) < q.rp) return true;
      return false;
    };
    const visible = labelled.filter((l) => !hidden(l));
    visible.sort((a, b) => b.d - a.d || a.p - b.p);   // far to near
    const shown = visible.slice(Math.max(0, visible.length - 400));
    ctx2d.font = '14px "DejaVu Sans", sans-serif';
    ctx2d.fillStyle = '#d0d0d0';
    ctx2d.textBaseline = 'middle';
    // Beside the disc, never over it (R1-RND-067).
    for (const l of shown) ctx2d.fillText(S.labels[l.p] || '', l.px + l.rp + 4, l.py);
    return shown.length;
  }

  // ---- the frame loop ----------------------------------------------------------------------------
  function resize() {
    if (S.fixedSize) return;
    S.width = Math.max(1, window.innerWidth);
    S.height = Math.max(1, window.innerHeight);
    for (const cv of [canvas, overlay]) { cv.width = S.width; cv.height = S.height; }
  }
  function stepInput(dt) {
    // Keyboard translation in the camera frame (WASD + QE) at the flight speed; Shift: follow-flow.
    const k = S.keys;
    const local = [(k.has('KeyD') ? 1 : 0) - (k.has('KeyA') ? 1 : 0), (k.has('KeyE') ? 1 : 0) - (k.has('KeyQ') ? 1 : 0),
                   (k.has('KeyS') ? 1 : 0) - (k.has('KeyW') ? 1 : 0)];
    const moving = local.some((v) => v !== 0);
    const follow = k.has('ShiftLeft') || k.has('ShiftRight');
    if (!moving && !follow) return;
    let v = [0, 0, 0];
    if (moving) v = mul(rotate(S.cam.orientation, norm(local)), flightSpeed(S.cam.position));
    S.cam = follow ? followFlowStep(S.cam, v, dt) : { ...S.cam, position: add(S.cam.position, mul(v, dt)) };
  }
  function animate(now) {
    const dt = S.lastFrame ? Math.min(0.1, (now - S.lastFrame) / 1000) : 0;
    // The frame time is the interval between displayed frames (GPU work included), smoothed; an
    // interval after a frame that was not drawn (below) is no frame's time.
    if (S.lastFrame && S.meta && G.drewLast) S.frameMs = S.frameMs ? 0.8 * S.frameMs + 0.2 * (now - S.lastFrame) : now - S.lastFrame;
    S.lastFrame = now;
    if (S.flights.length) {
      const fl = S.flights[0];
      const t = (now - fl.start) / 1000;
      S.cam = warpAt(fl.from, fl.to, t);
      if (t >= WARP_SECONDS) { S.flights.shift(); fl.done(S.cam); }
    } else if (S.meta) {
      stepInput(dt);
    }
    let moved = false;
    if (S.transition) {
      const tr = S.transition;
      const s = smoothstep((now - tr.start) / 1000 / tr.seconds);
      const pos = new Float64Array(S.pos.length);
      for (let i = 0; i < pos.length; ++i) pos[i] = tr.from[i] + (S.pos[i] - tr.from[i]) * s;
      S.shown = s >= 1 ? S.pos : pos;
      if (s >= 1) S.transition = null;
      moved = true;
    }
    if (S.meta) {
      if (S.frozenTime === null) S.time = now / 1000;
      const c = S.cam, f = cameraFrame(c);
      // The CPU side (tiers, order, bundles) is redone only when the camera or the positions moved.
      // While the camera moves, a recomputation that takes long (10^6 particles) runs at most once
      // per three of its own durations; the shaders place and tier the instances every frame, and
      // the frame after the camera stops is always exact.
      const key = JSON.stringify([c, S.width, S.height, S.gen]);
      const still = key === G.lastKey;
      G.lastKey = key;
      const due = still || !G.lastCpu || now - G.lastCpu >= 3 * (S.cpuMs || 0);
      const recompute = (moved || key !== G.tubeKey) && due;
      if (recompute) {
        G.lastCpu = now;
        const tc = performance.now();
        G.tubeKey = key;
        const cls = classify(c, f);
        G.cls = cls;
        uploadInstances(cls);
        uploadTubes(S.showEdges ? bundle(c, f, cls.size) : []);
        S.labelsDrawn = drawLabels(c, f, cls);
        S.tierCounts = cls.counts; S.visible = cls.visible;
        S.cpuMs = performance.now() - tc;
      }
      // With the flow frozen (?time=T), a frame that would repeat the drawn one is left out: the
      // canvas keeps its pixels (its buffer is preserved), and a page nobody moves costs no GPU
      // time (R1-VIEW-044). A frame() request, the camera, the size, a new generation, a transition
      // or the CPU side's redoing (content arriving, the first exact frame after a move) draws.
      G.drewLast = S.frozenTime === null || !still || recompute || moved || S.pending.length > 0 || G.drawn === 0;
      if (G.drewLast) {
        draw(c, f);
        status();
        G.drawn += 1;
      }
      const waiting = S.pending; S.pending = [];
      for (const r of waiting) r();
    }
    requestAnimationFrame(animate);
  }
  function status() {
    const c = S.cam, p = c.position;
    document.getElementById('status').textContent =
      `${S.meta.epoch} (generation ${S.gen}): ${S.n} particles, ${S.m} links   frame ${S.frameMs.toFixed(1)} ms, ${G.instanceCount} instances\n` +
      `T0 ${S.tierCounts[0]}  T1 ${S.tierCounts[1]}  T2 ${S.tierCounts[2]}  T3 ${S.tierCounts[3]}  Tinf ${S.tierCounts[4]}   ` +
      `eye ${p.map((v) => v.toFixed(1)).join(' ')}  fov ${c.fov.toFixed(0)}  tau ${tauCam(c).toPrecision(3)}`;
  }
  const nextFrame = () => new Promise((resolve) => S.pending.push(resolve));

  // ---- warp, portal step ---------------------------------------------------------------------
  // A new flight replaces one in progress (which resolves where it stopped) and starts from the
  // camera as it is now.
  function fly(to) {
    for (const f of S.flights.splice(0)) f.done(S.cam);
    return new Promise((resolve) => S.flights.push({ from: S.cam, to, start: performance.now(), done: resolve }));
  }
  async function find(query) {
    const r = await fetch('find?q=' + encodeURIComponent(query));
    const body = await r.json();
    if (!r.ok) throw new Error(body.error || `HTTP ${r.status}`);
    return body.particle;
  }
  async function warp(query) {
    const msg = document.getElementById('message');
    msg.textContent = '';
    let p;
    try { p = await find(query); } catch (e) { msg.textContent = e.message; throw e; }
    closePortal(false);
    return fly(warpEnd(S.cam, p));
  }
  // Portal step (R-1.0 9.3, R1-VIEW-022): fly along the line to the particle until its projected
  // diameter is past s_T0, open its T0 panel; Esc flies back along the same line.
  function portalPose(from, p) {
    const x = P(p);
    const d = 2 * S.radius[p] * focalPx(from) / S.meta.tiers.t0 * 0.9;
    const n = norm(sub(from.position, x));
    const position = add(x, mul(n, d));
    return { position, orientation: lookAt(position, x, rotate(from.orientation, [0, 1, 0])) || from.orientation.slice(), fov: from.fov };
  }
  async function portal(p) {
    const back = { ...S.cam };
    await fly(portalPose(S.cam, p));
    S.portal = { p, back };
    document.getElementById('portal-title').textContent = S.labels[p] || '';
    const c = S.content.get(p);
    document.getElementById('portal-body').textContent =
      `focus phi ${S.phi[p].toPrecision(4)}  ·  ${S.incident.offset[p + 1] - S.incident.offset[p]} links  ·  ` +
      (c ? `content: ${c.status === 'ok' ? c.type : c.status}` : 'no content given for this particle');
    await showContent(c);
    document.getElementById('portal').style.display = 'block';
    return S.cam;
  }
  // The particle's T0 content in the panel (R1-VIEW-072): an image as <img>, text as the text of a
  // <pre> (never parsed as HTML), anything else, and content that is missing, unreadable or
  // refused, as a card naming it.
  async function showContent(c) {
    const box = document.getElementById('portal-content');
    box.replaceChildren();
    if (!c) return;
    if (c.status === 'ok' && c.kind === 'image') {
      const img = document.createElement('img');
      img.id = 'portal-image';
      img.alt = c.source;
      img.src = c.url;
      box.append(img);
      await img.decode().catch(() => { box.replaceChildren(card('unreadable', `${c.source}: the browser cannot show it`)); });
      return;
    }
    if (c.status === 'ok' && c.kind === 'text') {
      const pre = document.createElement('pre');
      pre.id = 'portal-text';
      box.append(pre);
      try {
        const r = await fetch(c.url);
        if (!r.ok) throw new Error(`HTTP ${r.status}`);
        pre.textContent = await r.text();
      } catch (e) {
        box.replaceChildren(card('unreadable', `${c.source}: ${e.message}`));
      }
      return;
    }
    box.append(c.status === 'ok' ? card(c.type, c.source, 'other') : card(c.status, `${c.source}: ${c.reason}`));
  }
  function card(title, subtitle, status = title) {
    const d = document.createElement('div');
    d.id = 'portal-card';
    d.className = `card ${status}`;
    const t = document.createElement('div');
    t.className = 'title';
    t.textContent = title;
    const s = document.createElement('div');
    s.className = 'sub';
    s.textContent = subtitle;
    d.append(t, s);
    return d;
  }
  async function closePortal(flyBack = true) {
    const pt = S.portal;
    document.getElementById('portal').style.display = 'none';
    S.portal = null;
    if (pt && flyBack) return fly(pt.back);
    return S.cam;
  }
  function pick(x, y) {
    // The nearest particle surface under pixel (x, y), at T1 or T2.
    const c = S.cam, f = focalPx(c);
    const dirCam = norm([(x + 0.5 - S.width / 2) / f, -(y + 0.5 - S.height / 2) / f, -1]);
    const dir = rotate(c.orientation, dirCam);
    let best = -1, bestT = Infinity;
    for (let p = 0; p < S.n; ++p) {
      const oc = sub(P(p), c.position);
      const b = dot(dir, oc), r = S.radius[p];
      const disc = b * b - (dot(oc, oc) - r * r);
      if (disc < 0) continue;
      const t = b - Math.sqrt(disc);
      if (t > 0 && t < bestT) { bestT = t; best = p; }
    }
    if (best < 0) return -1;
    const s = 2 * S.radius[best] * f / len(sub(P(best), c.position));
    return s > S.meta.tiers.t2 && s <= S.meta.tiers.t0 ? best : -1;
  }

  // ---- input -------------------------------------------------------------------------------------
  function bindInput() {
    const q = document.getElementById('query');
    window.addEventListener('keydown', (e) => {
      if (e.target === q) { if (e.key === 'Enter') warp(q.value).catch(() => {}); return; }
      if (e.key === '/') { q.focus(); e.preventDefault(); return; }
      if (e.key === 'Escape') { closePortal(); return; }
      if (e.key === '-' || e.key === '=') {
        S.cam = { ...S.cam, fov: Math.min(110, Math.max(30, S.cam.fov + (e.key === '-' ? 5 : -5))) };
        return;
      }
      S.keys.add(e.code);
    });
    window.addEventListener('keyup', (e) => S.keys.delete(e.code));
    window.addEventListener('blur', () => S.keys.clear());
    document.getElementById('go').addEventListener('click', () => warp(q.value).catch(() => {}));
    document.getElementById('portal-back').addEventListener('click', () => closePortal());
    let drag = null;
    canvas.addEventListener('pointerdown', (e) => { drag = { x: e.clientX, y: e.clientY, moved: 0 }; canvas.setPointerCapture(e.pointerId); });
    canvas.addEventListener('pointermove', (e) => {
      if (!drag) return;
      const dx = e.clientX - drag.x, dy = e.clientY - drag.y;
      drag.x = e.clientX; drag.y = e.clientY; drag.moved += Math.abs(dx) + Math.abs(dy);
      // Mouse look: yaw about the camera's up, pitch about its right axis (6DOF, no fixed horizon).
      const k = (S.cam.fov * Math.PI / 180) / S.height;
      const yaw = axisAngle([0, 1, 0], -dx * k), pitch = axisAngle([1, 0, 0], -dy * k);
      S.cam = { ...S.cam, orientation: qnormalize(qmul(S.cam.orientation, qmul(yaw, pitch))) };
    });
    canvas.addEventListener('pointerup', (e) => {
      if (drag && drag.moved < 3) {
        const p = pick(e.clientX, e.clientY);
        if (p >= 0) portal(p);
      }
      drag = null;
    });
    canvas.addEventListener('wheel', (e) => {
      e.preventDefault();
      if (e.ctrlKey) {
        S.cam = { ...S.cam, fov: Math.min(110, Math.max(30, S.cam.fov + Math.sign(e.deltaY) * 2)) };
        return;
      }
      const step = flightSpeed(S.cam.position) * Math.min(1, Math.abs(e.deltaY) / 400) * Math.sign(e.deltaY);
      S.cam = { ...S.cam, position: add(S.cam.position, mul(rotate(S.cam.orientation, [0, 0, 1]), step)) };
    }, { passive: false });
    window.addEventListener('resize', resize);
  }

  // ---- boot and the testing hook -------------------------------------------------------------
  function vecParam(name) {
    const v = params.get(name);
    if (v === null) return null;
    const xs = v.split(',').map(Number);
    if (xs.length !== 3 || xs.some((x) => !Number.isFinite(x))) throw new Error(`?${name}= needs three numbers X,Y,Z`);
    return xs;
  }
  const params = new URLSearchParams(location.search);
  function cameraFromUrl() {
    const eye = vecParam('eye'), target = vecParam('target'), up = vecParam('up') || [0, 0, 1];
    if (eye && target) {
      const q = lookAt(eye, target, up);
      if (!q) throw new Error('?eye= and ?target= coincide, or ?up= is parallel to the view');
      S.cam = { ...S.cam, position: eye, orientation: q };
    } else if (eye || target) {
      throw new Error('?eye= and ?target= go together');
    }
    if (params.has('fov')) {
      const f = Number(params.get('fov'));
      if (!(f >= 30 && f <= 110)) throw new Error('?fov= must lie in [30, 110]');
      S.cam.fov = f;
    }
    const size = params.get('size');
    if (size) {
      const m = /^(\d{1,5})x(\d{1,5})$/.exec(size);
      if (!m || +m[1] < 1 || +m[2] < 1 || +m[1] > 16384 || +m[2] > 16384) throw new Error('?size= must be WIDTHxHEIGHT');
      S.fixedSize = true;
      S.width = +m[1]; S.height = +m[2];
      for (const cv of [canvas, overlay]) { cv.width = S.width; cv.height = S.height; }
    }
    S.showEdges = params.get('edges') !== '0';
    S.showLabels = params.get('labels') !== '0';
    S.showField = params.get('field') !== '0';
    // ?time=T freezes the flow animation at T seconds (r1 render --time); else it runs.
    if (params.has('time')) {
      const t = Number(params.get('time'));
      if (!Number.isFinite(t)) throw new Error('?time= must be a number of seconds');
      S.frozenTime = t; S.time = t;
    }
    // ?ui=0: the frame alone, for screenshots.
    if (params.get('ui') === '0') for (const id of ['bar', 'status', 'help']) document.getElementById(id).style.display = 'none';
  }
  const copyCam = (c) => ({ position: c.position.slice(), orientation: c.orientation.slice(), fov: c.fov });
  async function boot() {
    gpuInit();
    const meta = await (await fetch('meta.json')).json();
    const d = await loadGeneration(meta);
    S.cam = { position: meta.camera.position, orientation: meta.camera.orientation, fov: meta.camera.fov };
    resize();
    cameraFromUrl();
    install(d);
    await prepareContent();
    bindInput();
    requestAnimationFrame(animate);
    await nextFrame();
    setTimeout(pollGenerations, 1000);
  }
  const ready = boot();
  ready.catch((e) => { document.getElementById('message').textContent = 'r1 view: ' + e.message; });
  window.r1view = {
    ready,
    camera: () => copyCam(S.cam),
    setCamera: ({ eye, target, up = [0, 0, 1], fov }) => {
      const q = lookAt(eye, target, up);
      if (!q) throw new Error('setCamera: eye and target coincide, or up is parallel to the view');
      S.cam = { position: eye.slice(), orientation: q, fov: fov || S.cam.fov };
      return nextFrame().then(() => copyCam(S.cam));
    },
    warp: (query) => warp(query).then(copyCam),
    portal: (p) => portal(p).then(copyCam),
    exitPortal: () => closePortal().then(copyCam),
    find,
    followStep: (dt, vUser = [0, 0, 0]) => { S.cam = followFlowStep(S.cam, vUser, dt); return copyCam(S.cam); },
    nearest: (x) => nearestParticle(x),
    frame: () => nextFrame(),
    stats: () => ({ frameMs: S.frameMs, tiers: S.tierCounts.slice(), visible: S.visible, labels: S.labelsDrawn,
                    n: S.n, m: S.m, generation: S.gen, tau: tauCam(S.cam), flying: S.flights.length > 0,
                    portal: S.portal ? S.portal.p : -1, width: S.width, height: S.height, instances: G.instanceCount, cpuMs: S.cpuMs,
                    tubes: G.tubeCount, content: S.contentDrawn, drawn: G.drawn }),
  };
})();
