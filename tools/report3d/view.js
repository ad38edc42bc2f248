// The 3D view of `cullide report` (tools/plotting/view3d.py inlines this module, three.js and
// three's OrbitControls into the page; nothing is fetched). It draws one frame of a scene: every
// triangle light grey, the triangles of the oracle's intersecting pairs and of a method's missed and
// spurious pairs in their colours, with a dot on each such triangle so that a pair of small
// triangles stays visible from afar. Drag to rotate, wheel to zoom, right-drag to pan.
//
// The view's element says how far it got, for a reader and for tests (headless Chromium):
// data-view-state is "loading" (the page's markup), then "drawn" once a frame was rendered and
// read back, with data-view-pixels the number of canvas pixels that differ from the background
// (0: a blank canvas), or "error: ..." (no WebGL, bad data).
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';

const BACKGROUND = 0xffffff;
// Per triangle state (view3d.py): 0 other, 1 in an oracle pair, 2 missed, 3 spurious.
const COLORS = [0xc8c8c8, 0xf0a020, 0xe0201a, 0x1f6fe0];

function decode(base64, Type) {
    const bytes = Uint8Array.from(atob(base64), (c) => c.charCodeAt(0));
    return new Type(bytes.buffer, 0, bytes.byteLength / Type.BYTES_PER_ELEMENT);
}

// Non-indexed geometry: each triangle its own three vertices, so that it has its own colour and
// a flat normal.
function meshGeometry(positions, triangles, state, showOthers) {
    const keep = [];
    for (let t = 0; t < state.length; ++t) if (showOthers || state[t] !== 0) keep.push(t);
    const xyz = new Float32Array(keep.length * 9), rgb = new Float32Array(keep.length * 9);
    const color = new THREE.Color();
    keep.forEach((t, k) => {
        color.setHex(COLORS[state[t]]);
        for (let v = 0; v < 3; ++v) {
            const i = triangles[3 * t + v];
            xyz.set(positions.subarray(3 * i, 3 * i + 3), 9 * k + 3 * v);
            rgb.set([color.r, color.g, color.b], 9 * k + 3 * v);
        }
    });
    const g = new THREE.BufferGeometry();
    g.setAttribute('position', new THREE.BufferAttribute(xyz, 3));
    g.setAttribute('color', new THREE.BufferAttribute(rgb, 3));
    g.computeVertexNormals();
    return g;
}

// A dot at the centre of every triangle of a pair, drawn over the mesh.
function pairDots(positions, triangles, state) {
    const xyz = [], rgb = [];
    const color = new THREE.Color();
    for (let t = 0; t < state.length; ++t) {
        if (state[t] === 0) continue;
        const c = [0, 0, 0];
        for (let v = 0; v < 3; ++v)
            for (let a = 0; a < 3; ++a) c[a] += positions[3 * triangles[3 * t + v] + a] / 3;
        color.setHex(COLORS[state[t]]);
        xyz.push(...c);
        rgb.push(color.r, color.g, color.b);
    }
    const g = new THREE.BufferGeometry();
    g.setAttribute('position', new THREE.Float32BufferAttribute(xyz, 3));
    g.setAttribute('color', new THREE.Float32BufferAttribute(rgb, 3));
    const m = new THREE.PointsMaterial({ size: 5, sizeAttenuation: false, vertexColors: true, depthTest: false });
    const points = new THREE.Points(g, m);
    points.renderOrder = 1;
    return points;
}

// The canvas pixels that differ from the background (the test that the view is not blank).
function drawnPixels(renderer) {
    const gl = renderer.getContext();
    const w = gl.drawingBufferWidth, h = gl.drawingBufferHeight;
    const px = new Uint8Array(w * h * 4);
    gl.readPixels(0, 0, w, h, gl.RGBA, gl.UNSIGNED_BYTE, px);
    let n = 0;
    for (let i = 0; i < px.length; i += 4)
        if (px[i] !== 255 || px[i + 1] !== 255 || px[i + 2] !== 255) ++n;
    return n;
}

function show(root) {
    const data = JSON.parse(document.getElementById(root.dataset.source).textContent);
    const positions = decode(data.positions, Float32Array);
    const triangles = decode(data.triangles, Uint32Array);
    const state = decode(data.state, Uint8Array);
    const canvas = root.querySelector('canvas');
    const renderer = new THREE.WebGLRenderer({ canvas, antialias: true, preserveDrawingBuffer: true });
    renderer.setPixelRatio(window.devicePixelRatio || 1);
    renderer.setSize(canvas.clientWidth, canvas.clientHeight, false);
    renderer.setClearColor(BACKGROUND);

    const scene = new THREE.Scene();
    const material = new THREE.MeshLambertMaterial({ vertexColors: true, side: THREE.DoubleSide });
    const mesh = new THREE.Mesh(meshGeometry(positions, triangles, state, true), material);
    const dots = pairDots(positions, triangles, state);
    scene.add(mesh, dots, new THREE.AmbientLight(0xffffff, 1.2));

    mesh.geometry.computeBoundingSphere();
    const sphere = mesh.geometry.boundingSphere;
    const radius = sphere.radius > 0 ? sphere.radius : 1;
    const camera = new THREE.PerspectiveCamera(40, canvas.clientWidth / canvas.clientHeight, radius / 100,
                                               radius * 100);
    camera.position.copy(sphere.center).add(new THREE.Vector3(0.9, 0.6, 1.6).normalize().multiplyScalar(radius * 3));
    const light = new THREE.DirectionalLight(0xffffff, 2.0);
    light.position.set(0.3, 1, 1);
    camera.add(light);  // a headlight: the side facing the reader is lit from any angle
    scene.add(camera);

    const controls = new OrbitControls(camera, canvas);
    controls.target.copy(sphere.center);
    const render = () => renderer.render(scene, camera);
    controls.addEventListener('change', render);
    controls.update();

    const others = root.querySelector('input[name=others]');
    others.addEventListener('change', () => {
        mesh.geometry.dispose();
        mesh.geometry = meshGeometry(positions, triangles, state, others.checked);
        render();
    });
    const dotsBox = root.querySelector('input[name=dots]');
    dotsBox.addEventListener('change', () => { dots.visible = dotsBox.checked; render(); });

    render();
    root.dataset.viewPixels = String(drawnPixels(renderer));
    root.dataset.viewState = 'drawn';
}

for (const root of document.querySelectorAll('.view3d')) {
    try {
        show(root);
    } catch (e) {
        root.dataset.viewState = 'error: ' + e.message;
        root.querySelector('.view3d-status').textContent = 'The 3D view could not be drawn: ' + e.message;
    }
}
