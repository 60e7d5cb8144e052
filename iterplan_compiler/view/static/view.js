/* iterplan mission view: live (WebSocket deltas) or replay (a finished run, time slider).
   Read-only: the page never sends commands. Messages: see iterplan_compiler/view/snapshot.py. */
(function () {
  "use strict";
  var $ = function (id) { return document.getElementById(id); };
  var map = null, renderer = null, layers = {}, rects = {}, cellInfo = {}, M = null;
  var S = null;           // cumulative state
  var lastMsgAt = 0, wsOpen = false;

  function fresh() {
    return { track: [], done: new Set(), log: [], photos: [], it: {}, ctrl: null, pose: null,
             path: [], phase: "waiting for the vehicle", final: null };
  }

  // -- map ---------------------------------------------------------------------------------------
  function setupMap(m) {
    M = m;
    $("title").textContent = "iterplan: " + (m.title || m.name);
    document.title = "iterplan: " + (m.title || m.name);
    if (!map) {
      renderer = L.canvas({ padding: 0.5 });
      map = L.map("map", { preferCanvas: true, zoomSnap: 0.25, attributionControl: false });
      layers.cells = L.layerGroup().addTo(map);
      layers.marks = L.layerGroup().addTo(map);
      layers.track = L.polyline([], { color: "#1f4e9c", weight: 2, opacity: 0.85 }).addTo(map);
      layers.path = L.polyline([], { color: "#7c3aed", weight: 2, dashArray: "6 5" }).addTo(map);
      layers.photos = L.layerGroup().addTo(map);
      layers.first = L.layerGroup().addTo(map);
      var icon = L.divIcon({
        className: "aircraft-icon", iconSize: [30, 30], iconAnchor: [15, 15],
        html: '<svg id="aircraft-svg" width="30" height="30" viewBox="-15 -15 30 30">' +
              '<path d="M0,-13 L9,11 L0,6 L-9,11 Z" fill="#111" stroke="#fff" stroke-width="1.5"/></svg>'
      });
      layers.aircraft = L.marker(m.home, { icon: icon, interactive: false, zIndexOffset: 1000 });
    }
    layers.cells.clearLayers();
    layers.marks.clearLayers();
    rects = {}; cellInfo = {};
    var sensorOf = {};
    // Later sensors win; put fire last so it shows over P.
    var order = m.sensors.slice().sort(function (a, b) {
      return (a.name === "fire") - (b.name === "fire");
    });
    order.forEach(function (s) { s.cells.forEach(function (c) { sensorOf[c] = s; }); });
    for (var i = 0; i < m.cells.length; i++) {
      var c = m.cells[i], r = m.rects[i];
      cellInfo[c] = { name: m.names[i], sensor: sensorOf[c] || null };
      var rect = L.rectangle([[r[0], r[1]], [r[2], r[3]]], { renderer: renderer, interactive: true });
      rect.bindTooltip(m.names[i] + (sensorOf[c] ? " (" + sensorOf[c].name + ")" : ""));
      rects[c] = rect;
      rect.addTo(layers.cells);
      styleCell(c);
    }
    if (!m.per_cell) {
      L.rectangle(m.bounds, { renderer: renderer, color: "#666", weight: 1, fill: false })
        .addTo(layers.cells);
    }
    L.circleMarker(m.home, { radius: 6, color: "#000", fillColor: "#fff", fillOpacity: 1,
                             weight: 2 }).bindTooltip("home").addTo(layers.marks);
    map.fitBounds(m.bounds, { padding: [20, 20] });
    var leg = '<i style="background:#fff"></i>location';
    m.sensors.forEach(function (s) {
      leg += '<i style="background:' + s.colour + '"></i>' + s.name + " (" + s.count + ")";
    });
    leg += '<i style="background:#fff;border:2px solid #15803d"></i>done (D)' +
           '<i style="background:#fff;border:2px solid #1d4ed8"></i>next n' +
           '<i style="background:#1d4ed8;border-radius:50%"></i>sorter\'s first' +
           '<i style="background:#1f4e9c;height:2px"></i>track' +
           '<i style="background:#7c3aed;height:2px"></i>planned path' +
           '<i style="background:#ef4444;border-radius:50%"></i>photo';
    $("legend").innerHTML = leg + (m.per_cell ? "" : "<br>" + m.locations +
      " locations: only the sensor cells are drawn");
  }

  var firstKey = "";
  function drawFirst(cells) {      // the sorter's first few of R, numbered on the map
    var key = cells.join(",");
    if (key === firstKey) return;
    firstKey = key;
    layers.first.clearLayers();
    cells.forEach(function (c, i) {
      if (!rects[c]) return;
      L.marker(rects[c].getBounds().getCenter(), { interactive: false, icon: L.divIcon({
        className: "first-icon", iconSize: [16, 16], iconAnchor: [8, 8], html: String(i + 1) }) })
        .addTo(layers.first);
    });
  }

  function styleCell(c) {
    var r = rects[c];
    if (!r) return;
    var info = cellInfo[c], done = S && S.done.has(c), next = S && S.it && S.it.next_cell === c;
    var fill = info.sensor ? info.sensor.colour : "#ffffff";
    r.setStyle({
      fillColor: fill, fillOpacity: info.sensor ? (done ? 0.9 : 0.55) : (done ? 0.6 : 0.5),
      color: next ? "#1d4ed8" : (done ? "#15803d" : "#b5b5b5"),
      weight: next ? 3 : (done ? 1.5 : 0.6)
    });
    if (done && !info.sensor) r.setStyle({ fillColor: "#c8e6c9" });
  }

  // -- state -------------------------------------------------------------------------------------
  function apply(d) {
    var full = d.full || !S;
    if (full) {
      S = fresh();
      if (layers.track) { layers.track.setLatLngs([]); layers.photos.clearLayers(); }
    }
    var prevNext = S.it ? S.it.next_cell : null;
    ["t", "pose", "it", "ctrl", "counts", "photo_count", "compute_s", "overhead_pct", "mode",
     "link_ok", "simulated", "phase", "final", "target"].forEach(function (k) {
      if (k in d) S[k] = d[k];
    });
    if (d.track && d.track.length) {
      for (var i = 0; i < d.track.length; i++) { S.track.push(d.track[i]); }
      if (d.full) layers.track.setLatLngs(S.track);
      else d.track.forEach(function (p) { layers.track.addLatLng(p); });
    }
    var restyle = {};
    if (d.done_reset) { S.done.forEach(function (c) { restyle[c] = 1; }); S.done = new Set(); }
    if (d.done_new) d.done_new.forEach(function (c) { S.done.add(c); restyle[c] = 1; });
    if (d.log) { S.log = S.log.concat(d.log).slice(-60); }
    if (d.photos) d.photos.forEach(function (p) {
      S.photos.push(p);
      L.circleMarker([p[0], p[1]], { radius: 5, color: "#b91c1c", fillColor: "#ef4444",
                                     fillOpacity: 1, weight: 1 })
        .bindTooltip("photo " + p[2]).addTo(layers.photos);
    });
    if ("path" in d) { S.path = d.path; layers.path.setLatLngs(d.path || []); }
    if (S.it) { restyle[prevNext] = 1; restyle[S.it.next_cell] = 1; }
    if (d.it && layers.first) drawFirst(d.it.first_cells || []);
    if (full) Object.keys(rects).forEach(function (c) { restyle[c] = 1; });
    Object.keys(restyle).forEach(function (c) { if (c !== "null" && c !== "undefined") styleCell(+c); });
    render();
  }

  function fmtTime(t) {
    if (t === undefined || t === null) return "–";
    var m = Math.floor(t / 60), s = t - 60 * m;
    return (m ? m + " min " : "") + s.toFixed(1) + " s";
  }

  function render() {
    var st = $("status"), fin = S.final;
    st.textContent = S.phase || "";
    st.className = "status " + (fin ? (fin.ok ? "ok" : "bad") : (S.pose ? "flying" : "waiting"));
    $("mission-time").textContent = fmtTime(S.t);
    $("overhead").textContent = S.overhead_pct === null || S.overhead_pct === undefined ? "n/a"
      : S.overhead_pct.toFixed(1) + " %" + (fin ? " (summary)" : "");
    $("compute").textContent = S.compute_s !== undefined ? S.compute_s.toFixed(3) + " s" : "–";
    var cnt = S.counts || {};
    $("visits").textContent = (cnt.arrived || 0) + " / " + (S.photo_count || 0) +
      (cnt.steps !== undefined ? "  (" + cnt.steps + " steps)" : "");
    $("mode").textContent = S.mode || "–";
    var link = $("link");
    if (S.link_ok === undefined) { link.textContent = "–"; }
    else {
      var stale = !fin && wsOpen && Date.now() - lastMsgAt > 3000;
      link.textContent = (S.link_ok ? "vehicle ok" : "vehicle LINK LOST") +
        (S.simulated ? " (simulator)" : "") + "; view " + (wsOpen ? (stale ? "stale" : "live") : "replay/closed");
      link.className = S.link_ok && !stale ? "link-ok" : "link-bad";
    }
    var it = S.it || {};
    $("next").textContent = it.next === undefined ? "–" : (it.next === null ? "null (pass complete)" : it.next);
    $("done-count").textContent = it.done !== undefined ? String(it.done) : "0";
    $("remaining").textContent = it.remaining !== undefined ? it.remaining + " of " + it.total : "–";
    $("first").textContent = it.first && it.first.length ? it.first.join(", ") : "–";
    $("target").textContent = S.target ? S.target : "–";
    if (S.ctrl) {
      // The state alone rarely changes while the aircraft flies (a controller waits for
      // `arrived` in one state), so the text also says which step it is and what it waits for.
      var waits = S.ctrl.enabled.filter(function (a) { return !a[1]; }).map(function (a) { return a[0]; });
      var acts = S.ctrl.enabled.some(function (a) { return a[1]; });
      $("ctrl-state").textContent = "state " + S.ctrl.state +
        (S.counts && S.counts.steps !== undefined ? " (step " + S.counts.steps + ")" : "") +
        (S.final ? ": mission over" : (!acts && waits.length ? ": waiting for " + waits.join(" | ") : ""));
      $("enabled").innerHTML = S.ctrl.enabled.map(function (a) {
        return '<span class="' + (a[1] ? "c" : "u") + '" title="' +
               (a[1] ? "controllable" : "uncontrollable") + '">' + esc(a[0]) + "</span>";
      }).join("") || "none";
    } else if (S.ctrl_state !== undefined) {
      $("ctrl-state").textContent = "state " + S.ctrl_state;
      $("enabled").textContent = "–";
    }
    var ol = $("log"), html = "";
    for (var i = S.log.length - 1; i >= Math.max(0, S.log.length - 40); i--) {
      var e = S.log[i];
      html += '<li class="' + e[1] + '">' + e[0].toFixed(1) + " " + e[1] + " " + esc(e[2]) +
              (e[4] ? " @" + esc(e[4]) : "") + " [" + e[3] + "]</li>";
    }
    ol.innerHTML = html;
    if (S.pose && map) {
      var ll = [S.pose.lat, S.pose.lon];
      if (!map.hasLayer(layers.aircraft)) layers.aircraft.addTo(map);
      layers.aircraft.setLatLng(ll);
      var svg = document.getElementById("aircraft-svg");
      if (svg) svg.style.transform = "rotate(" + S.pose.heading + "deg)";
      $("aircraft-pos").textContent = S.pose.lat.toFixed(6) + ", " + S.pose.lon.toFixed(6) +
        "  hdg " + Math.round(S.pose.heading) + "°  " + S.pose.alt.toFixed(0) + " m  " +
        S.pose.gs.toFixed(1) + " m/s";
    }
  }

  function esc(s) {
    return String(s).replace(/[&<>"]/g, function (c) {
      return { "&": "&amp;", "<": "&lt;", ">": "&gt;", '"': "&quot;" }[c];
    });
  }

  // -- live --------------------------------------------------------------------------------------
  function connect() {
    var ws = new WebSocket((location.protocol === "https:" ? "wss://" : "ws://") + location.host + "/ws");
    ws.onopen = function () { wsOpen = true; };
    ws.onmessage = function (ev) {
      lastMsgAt = Date.now();
      var m = JSON.parse(ev.data);
      if (m.type === "map") { S = fresh(); setupMap(m); }
      else if (m.type === "state") apply(m);
    };
    ws.onclose = function () {
      wsOpen = false;
      if (S) {
        if (!S.final) { $("status").textContent = "view disconnected (mission process gone?)";
                        $("status").className = "status bad"; }
        render();
      }
      setTimeout(connect, 2000);
    };
  }
  setInterval(function () { if (S && wsOpen) render(); }, 1000);   // link staleness

  // -- replay ------------------------------------------------------------------------------------
  var R = null, playing = null;
  function setupReplay(data) {
    R = data;
    S = fresh();
    if (data.map) setupMap(data.map);
    else setupMap({ title: data.title, name: data.title, cells: [], rects: [], names: [],
                    sensors: [], home: data.home, bounds: data.bounds, per_cell: true,
                    locations: 0 });
    $("replay-bar").hidden = false;
    var sl = $("slider");
    sl.min = data.t0; sl.max = data.t1; sl.value = data.t1;
    sl.addEventListener("input", function () { showAt(+sl.value); });
    $("play").addEventListener("click", function () {
      if (playing) { clearInterval(playing); playing = null; $("play").textContent = "▶"; return; }
      if (+sl.value >= data.t1) sl.value = data.t0;
      $("play").textContent = "❚❚";
      var step = Math.max(0.5, (data.t1 - data.t0) / 600);
      playing = setInterval(function () {
        var v = Math.min(data.t1, +sl.value + step);
        sl.value = v; showAt(v);
        if (v >= data.t1) { clearInterval(playing); playing = null; $("play").textContent = "▶"; }
      }, 50);
    });
    showAt(data.t1);
  }

  function upto(arr, T) {     // number of rows with row[0] <= T (rows sorted by t)
    var lo = 0, hi = arr.length;
    while (lo < hi) { var mid = (lo + hi) >> 1; if (arr[mid][0] <= T) lo = mid + 1; else hi = mid; }
    return lo;
  }

  function showAt(T) {
    $("slider-time").textContent = fmtTime(T);
    var k = upto(R.track, T), tr = R.track.slice(0, k);
    layers.track.setLatLngs(tr.map(function (p) { return [p[1], p[2]]; }));
    var prevDone = S.done;
    S = fresh();
    S.t = T;
    if (k > 0) {
      var p = tr[k - 1], q = tr[Math.max(0, k - 2)];
      var heading = 0;
      if (k > 1) {
        var dy = p[1] - q[1], dx = (p[2] - q[2]) * Math.cos(p[1] * Math.PI / 180);
        heading = (Math.atan2(dx, dy) * 180 / Math.PI + 360) % 360;
      }
      S.pose = { lat: p[1], lon: p[2], alt: p[3], heading: heading, gs: R.speed || 0 };
    }
    var n = upto(R.events, T), ev = R.events.slice(0, n);
    S.log = ev.slice(-60);
    var done = 0;
    for (var i = 0; i < ev.length; i++) {
      var e = ev[i];
      if (e[1] === "c" && e[2] === "remove.next") done++;
      else if (e[1] === "c" && e[2] === "reset") done = 0;
    }
    S.it = { done: done, next: undefined };
    if (n) S.ctrl_state = ev[n - 1][3];
    var a = upto(R.arrivals, T);
    R.arrivals.slice(0, a).forEach(function (r) { if (r[3] !== null) S.done.add(r[3]); });
    S.counts = { arrived: a, steps: ev.filter(function (e) { return e[1] === "c" || e[1] === "u"; }).length };
    var ph = upto(R.photos, T);
    S.photo_count = ph;
    layers.photos.clearLayers();
    R.photos.slice(0, ph).forEach(function (p) {
      L.circleMarker([p[1], p[2]], { radius: 5, color: "#b91c1c", fillColor: "#ef4444",
                                     fillOpacity: 1, weight: 1 }).addTo(layers.photos);
    });
    S.mode = "replay";
    var end = T >= R.t1 - 1e-6;
    var s = R.summary || {};
    S.final = end ? { ok: !!s.ok, reason: s.reason } : null;
    S.phase = end ? (s.ok ? "mission completed" : "mission ended early: " + (s.reason || "?"))
                  : "replay at " + fmtTime(T);
    S.overhead_pct = end && s.overhead_pct !== undefined ? s.overhead_pct : null;
    S.compute_s = end ? s.compute_s : undefined;
    var all = {};
    prevDone.forEach(function (c) { all[c] = 1; });
    S.done.forEach(function (c) { all[c] = 1; });
    Object.keys(all).forEach(function (c) { styleCell(+c); });
    render();
  }

  fetch("/api/mode").then(function (r) { return r.json(); }).then(function (m) {
    if (m.mode === "replay") {
      fetch("/api/replay").then(function (r) { return r.json(); }).then(setupReplay);
    } else {
      connect();
    }
  });
})();
