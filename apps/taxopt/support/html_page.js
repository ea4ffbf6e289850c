
'use strict';
(function () {
const errors = [];
window.addEventListener('error', e => errors.push(String(e.message)));
const D = JSON.parse(document.getElementById('taxopt-data').textContent);
const tilt = D.tilt;
const MARKS = {
  point_collision: ['#d7191c', 'tool hits the part (shank, holder or a ball in the air)'],
  flute_gouge: ['#c51b7d', 'flutes reach into the part beyond the part tolerance'],
  move_collision: ['#fd8d3c', 'tool hits the part on the move into this point'],
  kept_collision: ['#2c7fb8', 'input axis kept: the optimised axes hit the part'],
  kept_peak_rate: ['#41b6c4', 'input axis kept: the optimised axes raised the peak rate'],
  kept_join: ['#a1dab4', 'blended between kept and optimised axes'],
  no_free_axis: ['#111111', 'no collision-free axis within the deviation cone'],
  axis_limit: ['#7b3294', tilt + ' or C at or past its range'],
  travel_exceeded: ['#8c510a', 'spindle outside the linear travel'],
  c_flip: ['#e6ab02', 'C turns by more than 90 deg on the move (after)'],
  c_flip_before: ['#fee391', 'C turned by more than 90 deg on the move (before)'],
};
const FINDING_OF = {
  point_collision: 'point_collision', flute_gouge: 'point_collision',
  move_collision: 'move_collision', kept_collision: 'input_axes_kept',
  kept_peak_rate: 'input_axes_kept', kept_join: 'input_axes_kept', no_free_axis: 'no_free_axis',
  axis_limit: 'axis_range_exceeded', travel_exceeded: 'travel_exceeded',
};
const fmt = (x, d) => (x === null || x === undefined) ? '-' : Number(x).toFixed(d);

// ---- 3D view -------------------------------------------------------------------------------
const canvas = document.getElementById('view');
const renderer = new THREE.WebGLRenderer({canvas, antialias: true, preserveDrawingBuffer: true});
renderer.setPixelRatio(1);
const background = new THREE.Color(0xf7f9fb);
renderer.setClearColor(background);
const scene = new THREE.Scene();
const groups = {part: new THREE.Group(), path: new THREE.Group(), before: new THREE.Group(),
                after: new THREE.Group(), markers: new THREE.Group(), highlight: new THREE.Group()};
Object.values(groups).forEach(g => scene.add(g));
const box = new THREE.Box3();
const grow = (x, y, z) => box.expandByPoint(new THREE.Vector3(x, y, z));
if (D.mesh) {
  const v = D.mesh.vertices;
  for (let i = 0; i < v.length; i += 3) grow(v[i], v[i + 1], v[i + 2]);
}
D.operations.forEach(o => { for (let i = 0; i < o.path.length; i += 3) grow(o.path[i], o.path[i + 1], o.path[i + 2]); });
if (box.isEmpty()) grow(0, 0, 0);
const centre = box.getCenter(new THREE.Vector3());
const diagonal = Math.max(box.getSize(new THREE.Vector3()).length(), 1e-3);
const axisLength = 0.05 * diagonal;

if (D.mesh) {
  const g = new THREE.BufferGeometry();
  g.setAttribute('position', new THREE.Float32BufferAttribute(D.mesh.vertices, 3));
  g.setIndex(D.mesh.faces);
  g.computeVertexNormals();
  const m = new THREE.MeshPhongMaterial({color: 0x9aa7b4, side: THREE.DoubleSide, flatShading: true,
                                         polygonOffset: true, polygonOffsetFactor: 1, polygonOffsetUnits: 1});
  groups.part.add(new THREE.Mesh(g, m));
}
// The axes' colour scale: 0 .. the largest a before or after over the page.
let aMax = 0;
D.operations.forEach(o => { aMax = Math.max(aMax, o.peaks.accel_before, o.peaks.accel_after); });
if (!(aMax > 0)) aMax = 1;
// Logarithmic: the input's peaks are often 100 times the output's (the demo: 2308 against 12).
const logScale = a => Math.log10(1 + Math.max(0, a)) / Math.log10(1 + aMax);
const ramp = t => {  // blue, green, yellow, red
  t = Math.min(1, Math.max(0, t));
  const stops = [[0.17, 0.35, 0.8], [0.1, 0.65, 0.3], [0.95, 0.8, 0.1], [0.85, 0.1, 0.1]];
  const s = t * (stops.length - 1), i = Math.min(stops.length - 2, Math.floor(s)), f = s - i;
  return stops[i].map((c, k) => c + f * (stops[i + 1][k] - c));
};
{
  const bar = document.getElementById('legend-bar'), ctx = bar.getContext('2d');
  for (let x = 0; x < bar.width; ++x) {
    const c = ramp(x / (bar.width - 1));  // t = log(1 + a) / log(1 + max)
    ctx.fillStyle = `rgb(${c.map(v => Math.round(255 * v)).join(',')})`;
    ctx.fillRect(x, 0, 1, bar.height);
  }
  document.getElementById('legend-max').textContent = fmt(aMax, 1);
  document.getElementById('legend-mid').textContent = fmt(Math.sqrt(1 + aMax) - 1, 1);
}
D.operations.forEach(o => {
  const g = new THREE.BufferGeometry();
  g.setAttribute('position', new THREE.Float32BufferAttribute(o.path, 3));
  const checked = o.checked;
  const m = checked ? new THREE.LineBasicMaterial({color: 0x1f5fbf})
                    : new THREE.LineDashedMaterial({color: 0x8a8a8a, dashSize: axisLength / 5, gapSize: axisLength / 8});
  const line = new THREE.Line(g, m);
  if (!checked) line.computeLineDistances();
  groups.path.add(line);
  for (const which of ['before', 'after']) {
    const pos = [], col = [];
    o.axes.forEach(([i, tip, axB, axA, gB, gA]) => {
      const ax = which === 'before' ? axB : axA;
      const c = ramp(logScale(which === 'before' ? gB : gA));
      pos.push(tip[0], tip[1], tip[2], tip[0] + axisLength * ax[0], tip[1] + axisLength * ax[1], tip[2] + axisLength * ax[2]);
      col.push(...c, ...c);
    });
    const ag = new THREE.BufferGeometry();
    ag.setAttribute('position', new THREE.Float32BufferAttribute(pos, 3));
    ag.setAttribute('color', new THREE.Float32BufferAttribute(col, 3));
    const mat = which === 'before'
      ? new THREE.LineDashedMaterial({vertexColors: THREE.VertexColors, dashSize: axisLength / 8, gapSize: axisLength / 10})
      : new THREE.LineBasicMaterial({vertexColors: THREE.VertexColors});
    const segs = new THREE.LineSegments(ag, mat);
    if (which === 'before') segs.computeLineDistances();
    groups[which].add(segs);
  }
});
// Markers, one Points object per kind (a point with several marks is in each of its kinds).
const markerCounts = {};
const markerObjects = {};
Object.keys(MARKS).forEach(kind => {
  const list = D.markers.filter(m => m.marks.split(';').includes(kind));
  markerCounts[kind] = list.length;
  if (!list.length) return;
  const g = new THREE.BufferGeometry();
  const tips = [];
  list.forEach(m => tips.push(m.tip[0], m.tip[1], m.tip[2]));
  g.setAttribute('position', new THREE.Float32BufferAttribute(tips, 3));
  const p = new THREE.Points(g, new THREE.PointsMaterial({color: MARKS[kind][0], size: 9, sizeAttenuation: false}));
  p.userData.list = list;
  markerObjects[kind] = p;
  groups.markers.add(p);
});
{
  const box2 = document.getElementById('marker-kinds');
  Object.keys(MARKS).forEach(kind => {
    const n = markerCounts[kind];
    const label = document.createElement('label');
    label.innerHTML = `<input type="checkbox" ${n ? 'checked' : 'disabled'}> <span class="swatch" style="background:${MARKS[kind][0]}"></span>${kind} (${n})`;
    label.title = MARKS[kind][1];
    label.querySelector('input').addEventListener('change', e => { if (markerObjects[kind]) markerObjects[kind].visible = e.target.checked; draw(); });
    box2.appendChild(label);
  });
  const unchecked = D.operations.reduce((s, o) => s + (o.checked ? 0 : o.points), 0);
  const nc = document.createElement('label');
  nc.innerHTML = `<input type="checkbox" disabled ${unchecked ? 'checked' : ''}> <span class="swatch" style="background:#8a8a8a"></span>not_checked (${unchecked}): the grey dashed path`;
  nc.title = 'no collision check judged the tool at these points';
  box2.appendChild(nc);
  const note = [];
  if (D.marker_total > D.markers.length) note.push(`markers: the first ${D.markers.length} of ${D.marker_total} points where a check fired are drawn`);
  if (D.decimation.plot_stride > 1) note.push(`plots and toolpath decimated: every ${D.decimation.plot_stride}th point of ${D.points}, with each stride's peaks of omega and a kept (${D.plotted_points} points shown)`);
  if (D.decimation.axes_every > 1) note.push(`tool axes drawn at every ${D.decimation.axes_every}th point`);
  if (D.mesh && D.mesh.triangles_shown < D.mesh.triangles_in) note.push(`part decimated from ${D.mesh.triangles_in} to ${D.mesh.triangles_shown} triangles (vertex clustering, cell ${fmt(D.mesh.cell_mm, 3)} mm)`);
  if (!D.collision_checked) note.push('NOT CHECKED: no part model, no collision check: the path is grey');
  document.getElementById('decimation').textContent = note.join('; ');
  window.taxoptNote = note.join('; ');
}
const camera = new THREE.PerspectiveCamera(40, canvas.width / canvas.height, diagonal / 1000, diagonal * 20);
camera.up.set(0, 0, 1);
camera.position.set(centre.x + 0.9 * diagonal, centre.y - 1.1 * diagonal, centre.z + 0.9 * diagonal);
camera.lookAt(centre);
scene.add(new THREE.HemisphereLight(0xffffff, 0x606870, 0.75));
const sun = new THREE.DirectionalLight(0xffffff, 0.55);
camera.add(sun);
sun.position.set(1, 1, 2);
scene.add(camera);
const controls = new THREE.OrbitControls(camera, canvas);
controls.target.copy(centre);
controls.screenSpacePanning = true;
controls.update();
function draw() { renderer.render(scene, camera); }
controls.addEventListener('change', draw);
for (const [id, g] of [['show-part', 'part'], ['show-path', 'path'], ['show-before', 'before'], ['show-after', 'after']]) {
  document.getElementById(id).addEventListener('change', e => { groups[g].visible = e.target.checked; draw(); });
}
// Picking a marker.
const raycaster = new THREE.Raycaster();
raycaster.params.Points.threshold = diagonal * 0.006;
const info = document.getElementById('info');
function angleDeg(u, v) {
  const d = Math.min(1, Math.max(-1, u[0] * v[0] + u[1] * v[1] + u[2] * v[2]));
  return Math.acos(d) * 180 / Math.PI;
}
function describe(m) {
  const o = D.operations[m.op];
  const lines = [`operation ${o.name}, point ${m.i}, CL line ${m.line}`];
  m.marks.split(';').forEach(k => lines.push(`• ${k}: ${MARKS[k] ? MARKS[k][1] : ''}`));
  lines.push(`${tilt} ${fmt(m.tilt_before, 3)} → ${fmt(m.tilt_after, 3)} deg, C ${fmt(m.c_before, 3)} → ${fmt(m.c_after, 3)} deg`);
  lines.push(`axis before (${m.axis_before.map(x => fmt(x, 4)).join(', ')}), after (${m.axis_after.map(x => fmt(x, 4)).join(', ')}): ${fmt(angleDeg(m.axis_before, m.axis_after), 3)} deg apart`);
  const codes = new Set(m.marks.split(';').map(k => FINDING_OF[k]).filter(Boolean));
  D.findings.filter(f => f.op === m.op && codes.has(f.code)).forEach(f => lines.push(`[${f.severity}] ${f.code}: ${f.message}`));
  return lines.join('\n');
}
canvas.addEventListener('click', ev => {
  const r = canvas.getBoundingClientRect();
  const mouse = new THREE.Vector2(((ev.clientX - r.left) / r.width) * 2 - 1, -((ev.clientY - r.top) / r.height) * 2 + 1);
  raycaster.setFromCamera(mouse, camera);
  const hits = raycaster.intersectObjects(Object.values(markerObjects).filter(p => p.visible));
  if (!hits.length) return;
  const m = hits[0].object.userData.list[hits[0].index];
  info.textContent = describe(m);
  selectPoint(m.op, m.i);
});
// The point a plot or a marker points at: a sphere at the tip.
const marker = new THREE.Mesh(new THREE.SphereGeometry(diagonal * 0.008, 16, 12), new THREE.MeshBasicMaterial({color: 0xff00ff}));
marker.visible = false;
groups.highlight.add(marker);
function showTip(o, row) {
  marker.position.set(o.path[3 * row], o.path[3 * row + 1], o.path[3 * row + 2]);
  marker.visible = true;
  draw();
}

// ---- plots ---------------------------------------------------------------------------------
const select = document.getElementById('op-select');
D.operations.forEach((o, k) => {
  const opt = document.createElement('option');
  opt.value = k; opt.textContent = `${o.name} (${o.points} points)`;
  select.appendChild(opt);
});
let charts = [];
function plotsOf(k) {
  const o = D.operations[k];
  const lim = D.machine;
  const vOf = l => l && l.velocity_deg_s, aOf = l => l && l.accel_deg_s2;
  const specs = [
    {title: `${tilt}, deg`, b: o.tilt_before, a: o.tilt_after, limits: lim.tilt_range_deg || [], what: `${tilt} range`},
    {title: 'C, deg', b: o.c_before, a: o.c_after, limits: lim.c_range_deg || [], what: lim.c_range_deg ? 'C range' : 'C is continuous: no range'},
    {title: 'ω, deg/s', b: o.omega_before, a: o.omega_after, limits: [vOf(lim.tilt_limits), vOf(lim.c_limits)].filter(x => x), what: `${tilt} and C velocity limits`},
    {title: 'a, deg/s²', b: o.accel_before, a: o.accel_after, limits: [aOf(lim.tilt_limits), aOf(lim.c_limits)].filter(x => x), what: `${tilt} and C acceleration limits`},
    {title: 'scheduled feed, mm/min', b: o.feed_before, a: o.feed_after, limits: o.programmed_feed_mm_min > 0 ? [o.programmed_feed_mm_min] : [], what: 'programmed feed'},
  ];
  const host = document.getElementById('plots');
  charts.forEach(c => c.destroy());
  charts = [];
  host.innerHTML = '';
  // Pass bands: [start arc, end arc] of each pass.
  const bands = [];
  for (let r = 0; r < o.pass.length; ++r) {
    if (r === 0 || o.pass[r] !== o.pass[r - 1]) bands.push([o.arc_mm[r], o.arc_mm[r], o.pass[r]]);
    bands[bands.length - 1][1] = o.arc_mm[r];
  }
  let syncing = false;
  specs.forEach(spec => {
    const title = document.createElement('div');
    title.className = 'plot-title';
    const name = document.createElement('span');
    name.textContent = `${spec.title} — limits: ${spec.limits.length ? spec.what + ' ' + spec.limits.map(x => fmt(x, 2)).join(' / ') : (spec.what.startsWith('C is') ? spec.what : 'none given')}`;
    // The values under the pointer on the title's line: a legend that follows the pointer
    // inside the plot lay over the title of the plot below it (the demo page did).
    const legend = document.createElement('span');
    legend.className = 'plot-legend';
    title.appendChild(name);
    title.appendChild(legend);
    const div = document.createElement('div');
    div.className = 'plot';
    host.appendChild(title);
    host.appendChild(div);
    const rows = o.arc_mm.map((x, r) => [x, spec.b[r], spec.a[r]]);
    const chart = new Dygraph(div, rows, {
      labels: ['arc mm', 'before', 'after'], colors: ['#9a9a9a', '#1f5fbf'], strokeWidth: 1.2,
      connectSeparatedPoints: false, legend: 'always', labelsDiv: legend, xlabel: 'arc length, mm',
      underlayCallback: (ctx, area, g) => {
        bands.forEach(([x0, x1, p]) => {
          if (p % 2) return;
          const l = g.toDomXCoord(x0), r = g.toDomXCoord(x1);
          ctx.fillStyle = 'rgba(60,90,130,0.07)';
          ctx.fillRect(l, area.y, Math.max(1, r - l), area.h);
        });
        ctx.strokeStyle = '#444'; ctx.lineWidth = 1;
        o.key_arc_mm.forEach(x => {
          const px = g.toDomXCoord(x);
          ctx.beginPath(); ctx.moveTo(px, area.y + area.h); ctx.lineTo(px, area.y + area.h - 6); ctx.stroke();
        });
        ctx.strokeStyle = '#d7191c'; ctx.setLineDash([6, 4]); ctx.lineWidth = 1.5;
        spec.limits.forEach(y => {
          const py = g.toDomYCoord(y);
          ctx.beginPath(); ctx.moveTo(area.x, py); ctx.lineTo(area.x + area.w, py); ctx.stroke();
        });
        ctx.setLineDash([]);
      },
      highlightCallback: (e, x, pts, row) => {
        showTip(o, row);
        if (syncing) return;
        syncing = true;
        charts.forEach(c => { if (c !== chart) c.setSelection(row); });
        syncing = false;
      },
      zoomCallback: (x0, x1) => {
        if (syncing) return;
        syncing = true;
        charts.forEach(c => { if (c !== chart) c.updateOptions({dateWindow: [x0, x1]}); });
        syncing = false;
      },
    });
    // The limits in the y range, so that a line above every value still shows.
    if (spec.limits.length) {
      const ys = spec.b.concat(spec.a).filter(v => v !== null).concat(spec.limits);
      const lo = ys.reduce((m, v) => Math.min(m, v)), hi = ys.reduce((m, v) => Math.max(m, v)), pad = 0.05 * Math.max(hi - lo, 1e-9);
      chart.updateOptions({valueRange: [lo - pad, hi + pad]});
    }
    charts.push(chart);
  });
}
function selectPoint(k, i) {
  if (Number(select.value) !== k) { select.value = k; plotsOf(k); }
  const o = D.operations[k];
  let row = 0;
  while (row + 1 < o.idx.length && o.idx[row + 1] <= i) ++row;
  charts.forEach(c => c.setSelection(row));
  showTip(o, row);
}
select.addEventListener('change', () => plotsOf(Number(select.value)));
if (D.operations.length) plotsOf(0);

// ---- what the page drew, for its tests -------------------------------------------------------
function countDrawn() {
  const gl = renderer.getContext();
  const w = gl.drawingBufferWidth, h = gl.drawingBufferHeight, px = new Uint8Array(w * h * 4);
  gl.readPixels(0, 0, w, h, gl.RGBA, gl.UNSIGNED_BYTE, px);
  const bg = [background.r, background.g, background.b].map(c => Math.round(255 * c));
  let n = 0;
  for (let i = 0; i < px.length; i += 4) {
    if (Math.abs(px[i] - bg[0]) + Math.abs(px[i + 1] - bg[1]) + Math.abs(px[i + 2] - bg[2]) > 24) ++n;
  }
  return {drawn: n, of: w * h};
}
const visible = Object.fromEntries(Object.entries(groups).map(([k, g]) => [k, g.visible]));
Object.entries(groups).forEach(([k, g]) => { g.visible = k === 'part'; });
draw();
const partPixels = countDrawn();
Object.entries(groups).forEach(([k, g]) => { g.visible = visible[k]; });
draw();
const allPixels = countDrawn();
// The first marker as a click shows it, and the plots and the 3D view pointed at it.
let firstMarker = null;
if (D.markers.length) {
  const m = D.markers[0];
  info.textContent = describe(m);
  firstMarker = {text: info.textContent, selected_row: (selectPoint(m.op, m.i), charts.length ? charts[0].getSelection() : -1)};
}
const peak = (key) => D.operations.reduce((m, o) => o[key].reduce((x, v) => Math.max(x, v), m), 0);
// Text of the plots (axis labels, ticks, legends) lying over a plot's title: counted.
const overlaps = (() => {
  const titles = [...document.querySelectorAll('#plots .plot-title')].map(t => t.getBoundingClientRect());
  const texts = [...document.querySelectorAll('#plots .plot *')]
      .filter(e => e.childElementCount === 0 && e.textContent.trim() !== '')
      .map(e => e.getBoundingClientRect()).filter(r => r.width > 0 && r.height > 0);
  const meet = (a, b) => a.left < b.right && b.left < a.right && a.top < b.bottom && b.top < a.bottom;
  return titles.reduce((n, t) => n + texts.filter(r => meet(t, r)).length, 0);
})();
const state = {
  operations: D.operations.length,
  points: D.operations.reduce((s, o) => s + o.points, 0),
  plotted_points: D.operations.reduce((s, o) => s + o.idx.length, 0),
  markers: D.markers.length,
  marker_counts: markerCounts,
  colliding_points: D.markers.filter(m => /point_collision|flute_gouge/.test(m.marks)).length,
  colliding_moves: markerCounts.move_collision || 0,
  peak_accel_after: peak('accel_after'), peak_accel_before: peak('accel_before'),
  peak_omega_after: peak('omega_after'), peak_omega_before: peak('omega_before'),
  mesh_triangles: D.mesh ? D.mesh.faces.length / 3 : 0,
  part_pixels: partPixels.drawn, drawn_pixels: allPixels.drawn, canvas_pixels: allPixels.of,
  charts: charts.length,
  label_title_overlaps: overlaps,
  plot_texts: document.querySelectorAll('#plots .plot-title, #plots .dygraph-axis-label').length,
  first_marker: firstMarker,
  note: window.taxoptNote,
  load_ms: performance.now(),
  errors,
};
window.taxoptState = state;
const out = document.getElementById('taxopt-state');
out.textContent = JSON.stringify(state);
console.log('taxopt-page-ready ' + JSON.stringify(state));
})();
