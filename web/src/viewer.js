// The 3D view of a run: the print's material regions (toggled, sectioned),
// the FEM's rest and deformed shapes coloured by |u| or von Mises stress with
// the goal probes, a caustic slab with its traced image on the receiver.
import * as THREE from 'three';
import { OrbitControls } from 'three/examples/jsm/controls/OrbitControls.js';
import { el, decode, fmt } from './util.js';

// Viridis, sampled at 9 stops (matplotlib's table).
const VIRIDIS = [[0.267, 0.005, 0.329], [0.283, 0.141, 0.458], [0.254, 0.265, 0.530], [0.207, 0.372, 0.553],
  [0.164, 0.471, 0.558], [0.128, 0.567, 0.551], [0.135, 0.659, 0.518], [0.267, 0.749, 0.441],
  [0.478, 0.821, 0.318], [0.741, 0.873, 0.150], [0.993, 0.906, 0.144]];

function viridis(t) {
  const x = Math.min(Math.max(t, 0), 1) * (VIRIDIS.length - 1);
  const i = Math.min(Math.floor(x), VIRIDIS.length - 2);
  const f = x - i;
  return VIRIDIS[i].map((a, k) => a + f * (VIRIDIS[i + 1][k] - a));
}

function geometryOf(mesh) {
  const geometry = new THREE.BufferGeometry();
  geometry.setAttribute('position', new THREE.BufferAttribute(decode(mesh.positions, Float32Array), 3));
  geometry.setIndex(new THREE.BufferAttribute(decode(mesh.indices, Uint32Array), 1));
  if (mesh.uv) geometry.setAttribute('uv', new THREE.BufferAttribute(decode(mesh.uv, Float32Array), 2));
  geometry.computeVertexNormals();
  return geometry;
}

class Viewer {
  constructor(data, images) {
    this.data = data;
    this.images = images;
    this.container = el('div', { class: 'viewer' });
    this.controlsBar = el('div', { class: 'controls' });
    this.legend = el('div', { class: 'legend', style: 'display:none' });
    this.container.append(this.legend);
    this.clip = new THREE.Plane(new THREE.Vector3(0, 0, -1), 1e9);
    this.objects = [];  // { name, object, toggle }
  }

  build() {
    const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
    renderer.setPixelRatio(window.devicePixelRatio || 1);
    renderer.localClippingEnabled = true;
    renderer.setClearColor(0xeef0f4);
    this.renderer = renderer;
    this.container.prepend(renderer.domElement);
    const scene = new THREE.Scene();
    this.scene = scene;
    scene.add(new THREE.HemisphereLight(0xffffff, 0x667080, 1.2));
    const sun = new THREE.DirectionalLight(0xffffff, 1.2);
    sun.position.set(1, 1.5, 2);
    scene.add(sun);
    const camera = new THREE.PerspectiveCamera(35, 1, 0.01, 1e6);
    camera.up.set(0, 0, 1);
    // A light that turns with the view, so no face the reader looks at is in the dark.
    const headlight = new THREE.DirectionalLight(0xffffff, 0.9);
    headlight.position.set(0.3, 0.5, 1);
    camera.add(headlight);
    scene.add(camera);
    this.camera = camera;
    this.controls = new OrbitControls(camera, renderer.domElement);
    this.controls.addEventListener('change', () => this.render());

    for (const mesh of this.data.meshes || []) this.addMesh(mesh);
    if (this.data.fem) this.addFem(this.data.fem);
    if (this.data.receiver) this.addReceiver(this.data.receiver);
    this.addSectionControl();
    this.fit();
    new ResizeObserver(() => this.resize()).observe(this.container);
    this.resize();
  }

  material(color, extra = {}) {
    return new THREE.MeshStandardMaterial({ color: new THREE.Color(...color), roughness: 0.65, metalness: 0.0,
      side: THREE.DoubleSide, clippingPlanes: [this.clip], ...extra });
  }

  toggle(name, object, swatch, checked = true) {
    object.visible = checked;
    const box = el('input', { type: 'checkbox' });
    box.checked = checked;
    box.addEventListener('change', () => { object.visible = box.checked; this.render(); });
    const label = el('label', {}, box, ' ', swatch ? el('span', { class: 'swatch', style: `background:${swatch}` }) : '', name);
    this.controlsBar.append(label);
    this.objects.push({ name, object });
  }

  addMesh(mesh) {
    const geometry = geometryOf(mesh);
    let material;
    if (mesh.texture !== undefined && this.images[mesh.texture]) {
      const texture = new THREE.TextureLoader().load(this.images[mesh.texture].data, () => this.render());
      texture.colorSpace = THREE.SRGBColorSpace;
      texture.flipY = true;
      texture.wrapS = THREE.RepeatWrapping;  // u past 1 across a projection's seam (texture_image.cpp)
      material = this.material([1, 1, 1], { map: texture });
    } else {
      material = this.material(mesh.color || [0.7, 0.7, 0.7], mesh.opacity ? { transparent: true, opacity: mesh.opacity } : {});
    }
    const object = new THREE.Mesh(geometry, material);
    this.scene.add(object);
    const c = new THREE.Color(...(mesh.color || [0.7, 0.7, 0.7]));
    const label = `${mesh.name} (${fmt(mesh.triangles)} of ${fmt(mesh.source_triangles)} triangles)`;
    this.toggle(label, object, mesh.texture !== undefined ? null : '#' + c.getHexString(), mesh.visible !== false);
  }

  addFem(fem) {
    const geometry = geometryOf(fem);
    const rest = geometry.getAttribute('position').array.slice();
    const u = decode(fem.displacement, Float32Array);
    const stress = decode(fem.von_mises_mpa, Float32Array);
    const count = rest.length / 3;
    const magnitude = new Float32Array(count);
    for (let v = 0; v < count; ++v) magnitude[v] = Math.hypot(u[3 * v], u[3 * v + 1], u[3 * v + 2]);
    const colors = new Float32Array(3 * count);
    geometry.setAttribute('color', new THREE.BufferAttribute(colors, 3));
    const material = new THREE.MeshStandardMaterial({ vertexColors: true, roughness: 0.7, side: THREE.DoubleSide,
      clippingPlanes: [this.clip] });
    const object = new THREE.Mesh(geometry, material);
    this.scene.add(object);
    const outline = new THREE.LineSegments(new THREE.EdgesGeometry(new THREE.BufferGeometry()
      .setAttribute('position', new THREE.BufferAttribute(rest, 3)).setIndex(geometry.getIndex()), 30),
    new THREE.LineBasicMaterial({ color: 0x555555, transparent: true, opacity: 0.5, clippingPlanes: [this.clip] }));
    this.scene.add(outline);
    this.toggle('rest shape (outline)', outline, '#555');
    this.toggle('FEM surface', object, null);

    const probes = new THREE.Group();
    const size = fem.probe_radius_mm;
    const dot = (p, color) => {
      const m = new THREE.Mesh(new THREE.SphereGeometry(size, 16, 12), new THREE.MeshStandardMaterial({ color }));
      m.position.set(p[0], p[1], p[2]);
      probes.add(m);
      return m;
    };
    const goals = [], achieved = [];
    for (const probe of fem.probes) {
      goals.push({ mesh: dot(probe.rest, 0xd62728), rest: probe.rest, u: probe.goal });
      achieved.push({ mesh: dot(probe.rest, 0x1f77b4), rest: probe.rest, u: probe.achieved });
    }
    this.scene.add(probes);
    this.toggle('probes: goal', probes, '#d62728');
    this.controlsBar.append(el('span', { class: 'muted' }, el('span', { class: 'swatch', style: 'background:#1f77b4' }), 'achieved'));

    // Displacements are often a few per cent of the part: drawn exaggerated by default, true scale one click away.
    let scale = fem.suggested_scale, field = 'u';
    const update = () => {
      const position = geometry.getAttribute('position');
      for (let i = 0; i < rest.length; ++i) position.array[i] = rest[i] + scale * u[i];
      position.needsUpdate = true;
      geometry.computeVertexNormals();
      for (const set of [goals, achieved]) {
        for (const p of set) p.mesh.position.set(p.rest[0] + scale * p.u[0], p.rest[1] + scale * p.u[1], p.rest[2] + scale * p.u[2]);
      }
      const values = field === 'u' ? magnitude : stress;
      const top = field === 'u' ? fem.max_displacement_mm : fem.p99_von_mises_mpa || fem.max_von_mises_mpa;
      for (let v = 0; v < count; ++v) colors.set(viridis(top > 0 ? values[v] / top : 0), 3 * v);
      geometry.getAttribute('color').needsUpdate = true;
      this.showLegend(field === 'u' ? '|u| (mm)' : 'von Mises (MPa)' + (fem.p99_von_mises_mpa ? ', top at p99' : ''), top);
      this.render();
    };
    const fieldSelect = el('select', {}, el('option', { value: 'u', text: 'colour: |u|' }),
      el('option', { value: 'vm', text: 'colour: von Mises stress' }));
    fieldSelect.addEventListener('change', () => { field = fieldSelect.value; update(); });
    const scaleInput = el('input', { type: 'range', min: '0', max: String(fem.suggested_scale * 4), step: 'any', value: String(scale) });
    const scaleText = el('span', { text: '×' + fmt(scale) });
    const setScale = (value) => { scale = value; scaleInput.value = String(value); scaleText.textContent = '×' + fmt(value); update(); };
    scaleInput.addEventListener('input', () => setScale(Number(scaleInput.value)));
    const button = (text, value) => el('button', { text, onclick: () => setScale(value) });
    this.controlsBar.append(fieldSelect, button('rest', 0), button('true scale ×1', 1),
      button(`exaggerated ×${fmt(fem.suggested_scale)}`, fem.suggested_scale), el('label', {}, 'deformation ', scaleInput, ' ', scaleText));
    update();
  }

  /// The receiver plane `distance_mm` below the slab's bottom, centred under
  /// it, with the traced image (cropped out of its picture) on it.
  addReceiver(receiver) {
    const image = this.images[receiver.image];
    if (!image || !image.data) return;
    const slab = new THREE.Box3();
    for (const { object } of this.objects) slab.expandByObject(object);
    const centre = slab.getCenter(new THREE.Vector3());
    const z = slab.min.z - receiver.distance_mm;
    const [w, h] = receiver.size_mm;
    const geometry = new THREE.PlaneGeometry(w, h);
    geometry.translate(centre.x, centre.y, z);
    const canvas = document.createElement('canvas');
    const [cx, cy, cw, ch] = receiver.crop;
    canvas.width = cw;
    canvas.height = ch;
    const texture = new THREE.CanvasTexture(canvas);
    texture.colorSpace = THREE.SRGBColorSpace;
    const picture = new Image();
    picture.onload = () => {
      canvas.getContext('2d').drawImage(picture, cx, cy, cw, ch, 0, 0, cw, ch);
      texture.needsUpdate = true;
      this.render();
    };
    picture.src = image.data;
    const object = new THREE.Mesh(geometry, new THREE.MeshBasicMaterial({ map: texture, side: THREE.DoubleSide }));
    this.scene.add(object);
    this.toggle(`receiver ${receiver.distance_mm} mm below: ${receiver.caption}`, object, null);
  }

  addSectionControl() {
    const box = new THREE.Box3();
    for (const { object } of this.objects) box.expandByObject(object);
    this.box = box;
    const axis = el('select', {}, ['off', 'x', 'y', 'z'].map((a) => el('option', { value: a, text: a === 'off' ? 'section: off' : `section ⟂ ${a}` })));
    const slider = el('input', { type: 'range', min: '0', max: '1', step: '0.001', value: '0.5' });
    const update = () => {
      if (axis.value === 'off') {
        this.clip.set(new THREE.Vector3(0, 0, -1), 1e9);
      } else {
        const k = { x: 0, y: 1, z: 2 }[axis.value];
        const lo = box.min.getComponent(k), hi = box.max.getComponent(k);
        const normal = new THREE.Vector3();
        normal.setComponent(k, -1);
        this.clip.set(normal, lo + Number(slider.value) * (hi - lo));
      }
      this.render();
    };
    axis.addEventListener('change', update);
    slider.addEventListener('input', update);
    this.controlsBar.append(axis, slider);
  }

  showLegend(title, top) {
    const bar = el('canvas', { class: 'bar', width: '160', height: '10' });
    const g = bar.getContext('2d');
    for (let x = 0; x < 160; ++x) {
      const [r, gg, b] = viridis(x / 159);
      g.fillStyle = `rgb(${r * 255},${gg * 255},${b * 255})`;
      g.fillRect(x, 0, 1, 10);
    }
    this.legend.replaceChildren(el('div', { text: title }), bar, el('div', {}, el('span', { text: '0' }),
      el('span', { style: 'float:right', text: fmt(top) })));
    this.legend.style.display = '';
  }

  fit() {
    const box = this.box;
    if (box.isEmpty()) return;
    const centre = box.getCenter(new THREE.Vector3());
    const radius = box.getSize(new THREE.Vector3()).length() / 2;
    const distance = radius / Math.sin((this.camera.fov * Math.PI) / 360);
    this.camera.position.copy(centre).add(new THREE.Vector3(0.9, -1.4, 0.9).normalize().multiplyScalar(distance * 1.05));
    this.camera.near = distance / 100;
    this.camera.far = distance * 100;
    this.camera.updateProjectionMatrix();
    this.controls.target.copy(centre);
    this.controls.update();
  }

  resize() {
    const w = this.container.clientWidth, h = this.container.clientHeight;
    if (!w || !h) return;
    this.renderer.setSize(w, h, false);
    this.camera.aspect = w / h;
    this.camera.updateProjectionMatrix();
    this.render();
  }

  render() {
    if (this.renderer) this.renderer.render(this.scene, this.camera);
  }
}

/// The viewer's section, or a line saying why there is none.
export function viewerSection(data, images) {
  const viewer = new Viewer(data, images);
  const note = el('p', { class: 'muted', text: data.note || 'Drag to turn, scroll to zoom, right-drag to pan. The full files are linked below.' });
  const wrapper = el('div', {}, viewer.controlsBar, viewer.container, note);
  return { element: wrapper, start: () => viewer.build() };
}
