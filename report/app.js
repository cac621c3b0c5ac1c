/* app.js - the shadowbench report's pages (results/site.c writes the data).
 * Every page is a shell that calls SB.start(kind): the page's data files are
 * loaded as scripts (file:// allows no fetch), each calling SB.data(...), and
 * the page is drawn when all have come. Charts are dygraphs. When the page is
 * drawn, <body> gets data-ready="yes", data-charts (charts drawn),
 * data-errors (script errors seen) for tests and tools to read. */
"use strict";
var SB = (function () {
  var errors = [], want = 0, got = {}, kind = "", charts = 0, started = performance.now();
  window.addEventListener("error", function (e) { errors.push(String(e.message || e)); mark(); });

  function el(tag, attrs, kids) {
    var e = document.createElement(tag);
    for (var k in attrs || {}) {
      if (k === "text") e.textContent = attrs[k];
      else if (k === "html") e.innerHTML = attrs[k];
      else e.setAttribute(k, attrs[k]);
    }
    (kids || []).forEach(function (c) { if (c) e.appendChild(typeof c === "string" ? document.createTextNode(c) : c); });
    return e;
  }
  function param(name) { return new URLSearchParams(location.search).get(name); }
  function load(src) {
    want++;
    var s = el("script", { src: src });
    s.onerror = function () { errors.push("cannot load " + src); fail("cannot load " + src); };
    document.head.appendChild(s);
  }
  function fail(msg) {
    var m = document.getElementById("main");
    m.innerHTML = "";
    m.appendChild(el("p", { "class": "error", text: msg }));
    mark();
  }
  function mark() {
    document.body.dataset.errors = String(errors.length);
    document.body.dataset.errorText = errors.join(" | ");
  }
  function done() {
    mark();
    /* how tall the one-line tables' rows are, in lines of their text (tests read it) */
    var most = 0;
    document.querySelectorAll("table.oneline tbody tr").forEach(function (tr) {
      var td = tr.querySelector("td");
      var line = td ? parseFloat(getComputedStyle(td).lineHeight) : 0;
      if (line > 0) most = Math.max(most, (tr.getBoundingClientRect().height - 8) / line);
    });
    document.body.dataset.maxRowLines = most.toFixed(2);
    document.body.dataset.charts = String(charts);
    document.body.dataset.readyMs = String(Math.round(performance.now() - started));
    document.body.dataset.ready = "yes";
  }
  function fmt(v, d) {
    if (v === null || v === undefined || v === "") return "";
    if (typeof v !== "number") return String(v);
    if (v !== 0 && (Math.abs(v) < 1e-3 || Math.abs(v) >= 1e6)) return v.toExponential(2);
    return String(+v.toPrecision(d || 4));
  }
  function pct(v) { return v === null || v === undefined ? "" : (v >= 0 ? "+" : "") + (100 * v).toFixed(1) + "%"; }
  /* "host|renderer|scene|path|WxH|technique|params" */
  function series(s) {
    var f = s.split("|");
    return { host: f[0], renderer: f[1], scene: f[2], path: f[3], size: f[4], technique: f[5], params: f.slice(6).join("|") };
  }
  function crumbs(parts) {
    var c = document.getElementById("crumbs");
    parts.forEach(function (p) { c.appendChild(document.createTextNode(" / ")); c.appendChild(p); });
  }

  /* a sortable, filterable table: cols [{name, get(row) -> value, cell(row) -> node|string, num}] */
  function table(cols, rows, opts) {
    opts = opts || {};
    var wrap = el("div", { "class": "table" });
    var filter = el("input", { type: "search", placeholder: "filter rows (words must all appear)", "class": "filter" });
    var count = el("span", { "class": "count" });
    var t = el("table", { "class": "sortable" + (opts.oneline ? " oneline" : "") }), thead = el("thead"), tbody = el("tbody");
    var sortBy = -1, dir = 1;
    var htr = el("tr");
    cols.forEach(function (c, i) {
      var th = el("th", { text: c.name, title: "sort by " + c.name });
      if (c.num) th.className = "num";
      th.onclick = function () { dir = sortBy === i ? -dir : 1; sortBy = i; draw(); };
      htr.appendChild(th);
    });
    thead.appendChild(htr);
    t.appendChild(thead);
    t.appendChild(tbody);
    function draw() {
      var words = filter.value.toLowerCase().split(/\s+/).filter(Boolean);
      var shown = rows.filter(function (r) {
        var text = cols.map(function (c) { var v = c.get(r); return v === null || v === undefined ? "" : String(v); })
                       .join(" ").toLowerCase() + " " + (opts.tags ? opts.tags(r) : "");
        return words.every(function (w) { return text.indexOf(w) >= 0; });
      });
      if (sortBy >= 0) {
        var g = cols[sortBy].get;
        shown.sort(function (a, b) {
          var x = g(a), y = g(b);
          if (x === y) return 0;
          if (x === null || x === undefined || x === "") return 1;
          if (y === null || y === undefined || y === "") return -1;
          return (x < y ? -1 : 1) * dir;
        });
      }
      tbody.innerHTML = "";
      shown.forEach(function (r) {
        var tr = el("tr");
        if (opts.rowClass) tr.className = opts.rowClass(r);
        cols.forEach(function (c) {
          var v = c.cell ? c.cell(r) : fmt(c.get(r));
          var td = el("td", c.num ? { "class": "num" } : {});
          if (v && v.nodeType) td.appendChild(v); else td.textContent = v === null || v === undefined ? "" : v;
          /* a one-line table cuts long cells: the whole text on hover */
          var full = c.get(r);
          if (opts.oneline && full !== null && full !== undefined && String(full).length > 24 && !td.title) td.title = String(full);
          tr.appendChild(td);
        });
        tbody.appendChild(tr);
      });
      count.textContent = shown.length + " of " + rows.length + " rows";
    }
    filter.oninput = draw;
    draw();
    wrap.appendChild(el("div", { "class": "tools" }, [filter, count]));
    wrap.appendChild(t);
    return wrap;
  }

  /* x ticks at whole numbers only (frames): 1, 2, 5 times a power of ten apart */
  function wholeTicks(min, max, pixels) {
    var want = Math.max(2, Math.floor(pixels / 60)), span = Math.max(1, max - min), step = 1;
    for (var k = 1; span / step > want; k++) step = [1, 2, 5][k % 3] * Math.pow(10, Math.floor(k / 3));
    var ticks = [];
    for (var v = Math.ceil(min / step) * step; v <= max; v += step) ticks.push({ v: v, label: String(v) });
    return ticks;
  }
  function chart(parent, data, opts, title, wide) {
    var box = el("div", { "class": "chart" + (wide ? " wide" : "") });
    var legend = el("div", { "class": "legend" });
    parent.appendChild(el("div", { "class": "chartbox" + (wide ? " wide" : "") }, [title ? el("h4", { text: title }) : null, box, legend]));
    opts.labelsDiv = legend;
    opts.legend = opts.legend || "always";
    var drawn = false;
    var user = opts.drawCallback;
    opts.drawCallback = function (g, first) {
      if (!drawn) { drawn = true; charts++; document.body.dataset.charts = String(charts); }
      if (user) user(g, first);
    };
    return new Dygraph(box, data, opts);
  }

  /* ---- index: the nights, the regressions, the series ---- */
  function pageIndex(d) {
    if (d.single && d.nights.length === 1) { location.replace("night.html?n=" + d.nights[0].id); return; }
    var m = document.getElementById("main");
    m.innerHTML = "";
    m.appendChild(el("h1", { text: "Results history" }));
    m.appendChild(el("p", { text: d.nights.length + " night(s), " + d.series.length + " series, from " + d.source }));
    var regs = d.changes.filter(function (c) { return c.regression; });
    var open = regs.filter(function (c) { return !c.accepted; }).length;
    regs.sort(function (a, b) { return (b.recent - a.recent) || (a.date_after < b.date_after ? 1 : -1); });
    var rs = el("section", { id: "regressions" }, [el("h2", { text: "Regressions (" + open + (regs.length > open ? ", and " + (regs.length - open) + " accepted" : "") + ")" })]);
    if (!regs.length) rs.appendChild(el("p", { text: "No regression found in any series." }));
    else rs.appendChild(changesTable(regs));
    m.appendChild(rs);
    var others = d.changes.filter(function (c) { return !c.regression; });
    if (others.length) {
      var os = el("section", { id: "improvements" }, [el("h2", { text: "Improvements (" + others.length + ")" })]);
      os.appendChild(changesTable(others));
      m.appendChild(os);
    }
    if (d.notes && d.notes.length) m.appendChild(notesList(d.notes, "Notes: annotations and machine changes (" + d.notes.length + ")"));
    var ns = el("section", { id: "nights" }, [el("h2", { text: "Nights" })]);
    ns.appendChild(table([
      { name: "night", get: function (n) { return n.id; }, cell: function (n) { return el("a", { href: "night.html?n=" + n.id, text: "#" + n.id }); }, num: true },
      { name: "date", get: function (n) { return n.date; } },
      { name: "host", get: function (n) { return n.host; } },
      { name: "commit", get: function (n) { return n.commit; } },
      { name: "runs", get: function (n) { return n.runs; }, num: true },
      { name: "ok", get: function (n) { return n.ok; }, num: true },
      { name: "failed", get: function (n) { return n.failed; }, num: true },
      { name: "unstable", get: function (n) { return n.unstable; }, num: true },
    ], d.nights.slice().reverse(), { rowClass: function (n) { return n.failed ? "failed" : n.unstable ? "unstable" : ""; } }));
    m.appendChild(ns);
    var changed = {};
    d.changes.forEach(function (c) { changed[c.sid] = (changed[c.sid] || 0) + 1; });
    var ss = el("section", { id: "series" }, [el("h2", { text: "Series" })]);
    ss.appendChild(table([
      { name: "series", get: function (i) { return d.labels[i]; }, cell: function (i) { return el("a", { href: "series.html?s=" + i, text: d.labels[i] }); } },
      { name: "host", get: function (i) { return series(d.series[i]).host; } },
      { name: "changes", get: function (i) { return changed[i] || 0; }, num: true },
    ], d.series.map(function (_, i) { return i; })));
    m.appendChild(ss);
    done();
  }
  /* annotations and machine changes, as a list */
  function notesList(notes, title) {
    var box = el("section", { "class": "notes" }, [el("h3", { text: title || "Notes" })]);
    var ul = el("ul", {});
    notes.forEach(function (n) {
      ul.appendChild(el("li", { "class": n.machine ? "machine" : n.accept ? "accepted" : "" }, [
        el("a", { href: "night.html?n=" + n.night, text: "night #" + n.night }), " " + n.date.slice(0, 10) + ": ",
        el("span", { text: (n.machine ? "machine: " : n.accept ? "accepted: " : "") + n.text + (n.series ? " (series " + n.series + ")" : "") })]));
    });
    box.appendChild(ul);
    return box;
  }
  function changeNote(c) { return [c.accepted ? "accepted" : "", c.note, c.machine].filter(Boolean).join(" · "); }
  function changesTable(list) {
    return table([
      { name: "series", get: function (c) { return c.label; }, cell: function (c) { return el("a", { href: "series.html?s=" + c.sid + "#" + c.metric, text: c.label }); } },
      { name: "metric", get: function (c) { return c.metric; } },
      { name: "first night after", get: function (c) { return c.night_after; }, cell: function (c) { return el("span", {}, [el("a", { href: "night.html?n=" + c.night_after, text: "#" + c.night_after }), " " + c.date_after.slice(0, 10) + " (before: ", el("a", { href: "night.html?n=" + c.night_before, text: "#" + c.night_before }), ")"]); } },
      { name: "before", get: function (c) { return c.before; }, num: true },
      { name: "after", get: function (c) { return c.after; }, num: true },
      { name: "change", get: function (c) { return c.rel; }, cell: function (c) { return pct(c.rel); }, num: true },
      { name: "z", get: function (c) { return c.z; }, num: true },
      { name: "p", get: function (c) { return c.p; }, num: true },
      { name: "commits", get: function (c) { return c.commit_before === c.commit_after ? c.commit_after + " (both)" : c.commit_before + ".." + c.commit_after; } },
      { name: "recent", get: function (c) { return c.recent ? "yes" : ""; } },
      { name: "notes", get: changeNote },
    ], list, { oneline: true, rowClass: function (c) { return c.regression ? (c.accepted ? "accepted" : c.recent ? "regression recent" : "regression") : "improvement"; } });
  }

  /* ---- a night ---- */
  function rowsOf(d) {
    return d.rows.map(function (r) { var o = {}; d.columns.forEach(function (c, i) { o[c] = r[i]; }); return o; });
  }
  function pageNight(d) {
    var m = document.getElementById("main");
    m.innerHTML = "";
    crumbs([el("a", { href: "night.html?n=" + d.id, text: "night #" + d.id })]);
    m.appendChild(el("h1", { text: "Night #" + d.id + ": " + d.date }));
    m.appendChild(el("p", { text: d.host + " · " + d.renderer + " · shadowbench " + d.version + " " + d.commit }));
    m.appendChild(el("details", {}, [el("summary", { text: "meta" }), el("pre", { text: d.meta })]));
    if (d.notes && d.notes.length) m.appendChild(notesList(d.notes, "Notes on this night"));
    var rows = rowsOf(d);
    var s = el("section", { id: "summary" }, [el("h2", { text: "Runs (" + rows.length + ")" }),
      el("p", { "class": "keyline", html: "<span class='unstable'>unstable timings (stable=no)</span> <span class='warned'>warnings</span> <span class='failed'>failed</span> · click a header to sort · long cells are cut: hover for the whole, or open the run" })]);
    var num = function (name) { return { name: name, get: function (r) { return r[name]; }, num: true }; };
    /* the parameters every run of a technique shares are said once, above the table; a row shows the rest */
    var shared = {};
    rows.forEach(function (r) {
      var items = (r.params || "").split(":").filter(Boolean);
      if (!(r.technique in shared)) shared[r.technique] = items;
      else shared[r.technique] = shared[r.technique].filter(function (i) { return items.indexOf(i) >= 0; });
    });
    var own = function (r) {
      return (r.params || "").split(":").filter(function (i) { return i && shared[r.technique].indexOf(i) < 0; }).join(":");
    };
    var common = el("details", {}, [el("summary", { text: "parameters every run of a technique shares (left out of the rows)" })]);
    Object.keys(shared).forEach(function (t) { if (shared[t].length) common.appendChild(el("p", { "class": "small", text: t + ": " + shared[t].join(":") })); });
    s.appendChild(common);
    s.appendChild(table([
      { name: "run", get: function (r) { return r.run_id; }, cell: function (r) { return el("a", { href: "run.html?n=" + d.id + "&r=" + r.run_id, text: r.run_id }); } },
      { name: "scene", get: function (r) { return r.scene; } },
      { name: "path", get: function (r) { return r.path; } },
      { name: "technique", get: function (r) { return r.technique; } },
      { name: "params", get: function (r) { return r.params; }, cell: function (r) { return el("span", { "class": "params", title: r.params, text: own(r) }); } },
      { name: "light", get: function (r) { return r.light || ""; } },   /* a sized light's runs beside the hard ones */
      { name: "size", get: function (r) { return r.width + "x" + r.height; } },
      { name: "status", get: function (r) { return r.status; } },
      { name: "stable", get: function (r) { return r.stable; } },
    ].concat(d.night_columns.map(num), [   /* the column table's night columns (SB_USE_NIGHT) */
      { name: "warnings / reason", get: function (r) { return (r.reason || "") + (r.warnings || "") + (r.unstable_reason ? " " + r.unstable_reason : ""); } },
    ]), rows, {
      oneline: true,
      rowClass: function (r) { return r.status === "failed" ? "failed" : r.stable === "no" ? "unstable" : r.warnings ? "warned" : ""; },
      tags: function (r) { return (r.stable === "no" ? "unstable" : "") + (r.warnings ? " warned" : ""); }
    }));
    m.appendChild(s);
    if (d.pairs.length) {
      var ps = el("section", { id: "pairs" }, [el("h2", { text: "Pairs" })]);
      d.pairs.forEach(function (p) {
        ps.appendChild(el("h3", { text: p.key }));
        if (p.shared) ps.appendChild(el("details", {}, [el("summary", { text: "parameters every pair shares (left out of the rows)" }),
          el("p", { "class": "small fold", text: p.shared })]));
        ps.appendChild(table(p.columns.map(function (c, i) {
          return { name: c, get: function (r) { return r[i]; }, num: typeof p.rows[0][i] === "number" };
        }), p.rows, { oneline: true, rowClass: function (r) { var v = r[r.length - 1]; return /regress|worse|UNSTABLE/i.test(String(v)) ? "warned" : ""; } }));
      });
      m.appendChild(ps);
    }
    /* the columns of each role (the column table's): time and error, flicker, the memory the budget limits */
    var T = d.roles.time, E = d.roles.error, F = d.roles.flicker, M = d.roles.memory;
    /* a memory budget (MiB; ?budget=M in the address): the fronts of the runs that hold no more */
    var budget = el("input", { type: "number", min: "0", step: "any", id: "budget", value: param("budget") || "",
      placeholder: "any", style: "width:7em" });
    var plots = el("div", {});
    var fs = el("section", { id: "fronts" }, [el("h2", { text: "Time against error, per scene" }),
      el("p", { text: "Each point a run (median frame time, mean error rate against the exact reference; beside it, the mean flicker rate of its twins a display frame later); the line joins the runs no other run beats on both." }),
      el("p", {}, [el("label", { "for": "budget", text: "memory budget, MiB of shadow storage (" + M + "): " }), budget,
        el("span", { "class": "small", text: " runs that hold more are left out of the fronts; empty: every run" })]),
      plots]);
    function drawFronts() {
      plots.textContent = "";
      var cap = parseFloat(budget.value), scenes = {}, over = 0;
      rows.forEach(function (r) {
        if (r.status !== "ok" || typeof r[E] !== "number" || typeof r[T] !== "number") return;
        if (!isNaN(cap) && typeof r[M] === "number" && r[M] > cap) { over++; return; }
        (scenes[r.scene] = scenes[r.scene] || []).push(r);
      });
      if (!isNaN(cap)) plots.appendChild(el("p", { "class": "small", id: "budget-note",
        text: over + " run(s) over " + cap + " MiB left out" }));
      Object.keys(scenes).forEach(function (sc) {
        var label = function (r) { var p = own(r); return r.technique + (p ? ":" + p : "") + (typeof r[M] === "number" ? " (" + fmt(r[M], 3) + " MiB)" : ""); };
        front(plots, sc, scenes[sc].map(function (r) {
          return { technique: r.technique, label: label(r), x: r[T], y: r[E] };
        }));
        /* beside it, flicker: the runs that measured it (a twin a display frame later) */
        var fl = scenes[sc].filter(function (r) { return typeof r[F] === "number"; });
        if (fl.length) front(plots, sc + ": flicker", fl.map(function (r) {
          return { technique: r.technique, label: label(r), x: r[T], y: r[F] };
        }), { ylabel: "flicker rate" });
      });
      if (!Object.keys(scenes).length) plots.appendChild(el("p", { text: "No run of this night measured its error" + (isNaN(cap) ? "." : " within the budget.") }));
    }
    budget.addEventListener("change", drawFronts);
    drawFronts();
    m.appendChild(fs);
    done();
  }
  /* Time against error: each point {technique, label, x, y[, front, chosen]}, a series per technique, the
   * front joined (the points' own flags, else the points no other beats on both), the chosen one ringed and
   * a bound (o.bound on o.boundOn "x" or "y") dashed. The night page and tune's front page draw it. */
  function front(parent, title, pts, o) {
    o = o || {};
    var techs = [];
    pts.forEach(function (p) { if (techs.indexOf(p.technique) < 0) techs.push(p.technique); });
    pts = pts.slice().sort(function (a, b) { return a.x - b.x || a.y - b.y; });
    var flagged = pts.some(function (p) { return p.front !== undefined; });
    var best = Infinity, onFront = [];
    pts.forEach(function (p) {
      if (flagged ? p.front : p.y < best) { best = Math.min(best, p.y); onFront.push(p); }
    });
    var data = pts.map(function (p) {
      var row = [p.x];
      techs.forEach(function (t) { row.push(t === p.technique ? p.y : null); });
      row.push(onFront.indexOf(p) >= 0 ? p.y : null);
      return row;
    });
    var series = {};
    techs.forEach(function (t) { series[t] = { strokeWidth: 0, drawPoints: true, pointSize: 4 }; });
    series.front = { strokeWidth: 1.5, drawPoints: false, connectSeparatedPoints: true, color: "#888" };
    var chosen = pts.filter(function (p) { return p.chosen; })[0];
    /* readable axes: a log scale where the figures span more than 20x (and are all > 0), and the range of the
       points with a margin, so that no point sits on an edge */
    var xs = pts.map(function (p) { return p.x; }), ys = pts.map(function (p) { return p.y; });
    function range(v, log) {
      var lo = Math.min.apply(null, v), hi = Math.max.apply(null, v);
      if (log) return [lo / Math.pow(hi / lo, 0.08), hi * Math.pow(hi / lo, 0.08)];
      var pad = (hi - lo) * 0.08 || Math.abs(hi) * 0.1 || 1;
      return [lo - pad < 0 && lo >= 0 ? 0 : lo - pad, hi + pad];
    }
    function wide(v) { var lo = Math.min.apply(null, v), hi = Math.max.apply(null, v); return lo > 0 && hi / lo > 20; }
    var logx = !o.fromZero && wide(xs), logy = !o.fromZero && wide(ys);
    var hover = el("div", { "class": "small hover", text: "hover a point for its run" });
    var opts = { labels: ["time"].concat(techs, ["front"]), series: series, xlabel: (o.xlabel || "median frame time (ms)") + (logx ? ", log scale" : ""),
      ylabel: (o.ylabel || "error rate") + (logy ? ", log scale" : ""), legend: "always", highlightCircleSize: 5,
      dateWindow: range(xs, logx), valueRange: range(ys, logy), logscale: logy,
      highlightCallback: function (e, x, points, row) {
        var p = pts[row];
        if (p) hover.textContent = p.label + ": " + fmt(p.x) + " ms, " + fmt(p.y);
      },
      axes: { x: { logscale: logx, axisLabelFormatter: function (v) { return fmt(v, 3); } },
              y: { axisLabelWidth: 70, axisLabelFormatter: function (v) { return fmt(v, 3); } } },
      underlayCallback: function (ctx, area, g) {
        if (typeof o.bound === "number") {   /* the bound, dashed red across the plot */
          ctx.save();
          ctx.strokeStyle = "#d00";
          ctx.setLineDash([5, 4]);
          ctx.beginPath();
          if (o.boundOn === "x") { var bx = g.toDomXCoord(o.bound); ctx.moveTo(bx, area.y); ctx.lineTo(bx, area.y + area.h); }
          else { var by = g.toDomYCoord(o.bound); ctx.moveTo(area.x, by); ctx.lineTo(area.x + area.w, by); }
          ctx.stroke();
          ctx.restore();
        }
        if (chosen) {
          ctx.save();
          ctx.strokeStyle = "#d00";
          ctx.lineWidth = 2;
          ctx.beginPath();
          ctx.arc(g.toDomXCoord(chosen.x), g.toDomYCoord(chosen.y), 9, 0, 2 * Math.PI);
          ctx.stroke();
          ctx.restore();
        }
      } };
    /* tune's page: both axes from zero, and far enough to show the bound */
    if (o.fromZero) {
      var xs = pts.map(function (p) { return p.x; }), ys = pts.map(function (p) { return p.y; });
      if (typeof o.bound === "number") (o.boundOn === "x" ? xs : ys).push(o.bound);
      opts.dateWindow = [0, Math.max.apply(null, xs.concat([0])) * 1.08 || 1];
      opts.valueRange = [0, Math.max.apply(null, ys.concat([0])) * 1.08 || 1];
    }
    chart(parent, data, opts, title);
    parent.appendChild(hover);
    parent.appendChild(el("p", { "class": "small fold", text: "front: " + onFront.map(function (p) { return p.label + " " + fmt(p.x) + " ms, " + fmt(p.y); }).join(" · ") }));
  }

  /* ---- tune's search: front.html ---- */
  function pageFront(d) {
    var m = document.getElementById("main");
    m.innerHTML = "";
    m.appendChild(el("h1", { text: d.title }));
    m.appendChild(el("p", { text: d.about }));
    front(m, null, d.points, { xlabel: d.xlabel, ylabel: d.ylabel, bound: d.bound, boundOn: d.bound_on, fromZero: true });
    m.appendChild(el("p", { "class": "small", text: "Dashed red: the bound. Ringed: " + d.chosen_is + "." }));
    m.appendChild(table([
      { name: "setting", get: function (p) { return p.label; } },
      { name: "time (ms)", get: function (p) { return p.x; }, num: true },
      { name: "error", get: function (p) { return p.y; }, num: true },
      { name: "frames", get: function (p) { return p.frames; }, num: true },
      { name: "front", get: function (p) { return p.front ? "yes" : ""; } },
      { name: "chosen", get: function (p) { return p.chosen ? "yes" : ""; } },
    ], d.points, { rowClass: function (p) { return p.chosen ? "improvement" : ""; } }));
    done();
  }

  /* ---- a run ---- */
  function pageRun(night, frames) {
    var id = param("r"), m = document.getElementById("main");
    var r = rowsOf(night).filter(function (x) { return x.run_id === id; })[0];
    if (!r) return fail("no run " + id + " in night #" + night.id);
    m.innerHTML = "";
    crumbs([el("a", { href: "night.html?n=" + night.id, text: "night #" + night.id }), el("span", { text: "run " + id })]);
    m.appendChild(el("h1", { text: r.scene + " " + r.technique + (r.params ? ":" + r.params : "") }));
    m.appendChild(el("p", { text: "path " + r.path + " · " + r.width + "x" + r.height + " · status " + r.status + (r.reason ? " (" + r.reason + ")" : "") + " · stable " + (r.stable || "n/a") + (r.warnings ? " · warnings: " + r.warnings : "") }));
    var fr = frames.runs[id] || [], c = frames.columns;
    var at = function (name) { return c.indexOf(name); };
    var stages = frames.stages.filter(function (s) {   // the stage times, named by the tool (sb_stage_names)
      return fr.some(function (f) { return typeof f[at(s)] === "number"; });
    });
    var cs = el("section", { id: "frames" }, [el("h2", { text: "Frames" })]);
    if (!fr.length) cs.appendChild(el("p", { text: "No per-frame figures (the run did not measure frames)." }));
    else if (!stages.length && fr.every(function (f) { return f[at("draw_calls")] === null; }))   /* score's frames */
      cs.appendChild(el("p", { text: "Nothing timed or counted here: the frames are another renderer's, scored against " +
        "the reference by shadowbench score. Its errors are in the night's table." }));
    else {
      var x = function (f, i) { return i; };
      chart(cs, fr.map(function (f, i) { return [x(f, i)].concat(stages.map(function (s) { return f[at(s)] === null ? 0 : f[at(s)]; })); }),
        { labels: ["frame"].concat(stages), stackedGraph: true, fillGraph: true, xlabel: "measured frame", ylabel: "ms", axes: { x: { ticker: wholeTicks } } }, "Frame time by stage (stacked)");
      frames.charts.forEach(function (ch) {   /* the column table's charted columns (sb_frame_col.chart) */
        chart(cs, fr.map(function (f, i) { return [i].concat(ch.columns.map(function (n) { return f[at(n)]; })); }),
          { labels: ["frame"].concat(ch.columns), xlabel: "measured frame", axes: { x: { ticker: wholeTicks } } }, ch.title);
      });
    }
    m.appendChild(cs);
    var imgs = night.images.filter(function (n) { return n.indexOf(id + "_f") === 0; });
    var is = el("section", { id: "images" }, [el("h2", { text: "Images of evaluated frames" })]);
    if (!imgs.length) is.appendChild(el("p", { text: "None: the run was made without --images." }));
    var byFrame = {};
    imgs.forEach(function (n) { var f = n.slice(id.length + 2, id.length + 6); (byFrame[f] = byFrame[f] || []).push(n); });
    /* the raw targets; then, with --flip, the frame as a player sees it beside the reference's and their FLIP map */
    var rows = [{ kinds: ["color", "vis", "ref", "error", "cascades", "flicker"] },
                { kinds: ["shaded", "shaded_ref", "flip"], title: "As a player sees it (--flip)",
                  caption: { shaded: "shaded: the technique", shaded_ref: "shaded: the reference", flip: "FLIP (white: 1)" } }];
    Object.keys(byFrame).sort().forEach(function (f) {
      is.appendChild(el("h3", { text: "frame " + (+f) }));
      rows.forEach(function (r) {
        var row = el("div", { "class": "imgrow" });
        r.kinds.forEach(function (k) {
          var n = byFrame[f].filter(function (x) { return x.indexOf("_" + k + ".png") > 0; })[0];
          if (!n) return;
          var img = el("img", { src: "images/" + night.id + "/" + n, alt: k + " of frame " + f, loading: "eager" });
          img.onload = function () { if (img.naturalWidth > 0) document.body.dataset.imagesLoaded = String(+(document.body.dataset.imagesLoaded || 0) + 1); };
          img.onerror = function () { errors.push("image " + n + " did not load"); mark(); };
          row.appendChild(el("figure", {}, [img, el("figcaption", { text: (r.caption && r.caption[k]) || k })]));
        });
        if (!row.childNodes.length) return;
        if (r.title) is.appendChild(el("h4", { text: r.title }));
        is.appendChild(row);
      });
    });
    m.appendChild(is);
    done();
  }

  /* ---- a series ---- */
  function pageSeries(d) {
    var m = document.getElementById("main"), s = series(d.series);
    m.innerHTML = "";
    crumbs([el("span", { text: d.label })]);
    m.appendChild(el("h1", { text: d.label }));
    m.appendChild(el("p", { text: s.host + " · " + s.renderer }));
    m.appendChild(el("details", {}, [el("summary", { text: "all parameters" }), el("p", { "class": "small fold", text: s.params || "none" })]));
    var notes = (d.notes || []).map(function (n) { return { date: new Date(n.date), n: n }; });
    if (notes.length) m.appendChild(notesList(d.notes, "Notes on this series (dashed lines on the charts)"));
    Object.keys(d.metrics).forEach(function (name) {
      var mt = d.metrics[name];
      if (!mt.nights.length) return;
      var sec = el("section", { id: name }, [el("h2", { text: name })]);
      m.appendChild(sec);   /* in the page before the chart is made: a wide chart takes the page's width */
      var hasCi = mt.nights.some(function (n) { return n[3] !== null; });
      var data = mt.nights.map(function (n) {
        var c = n[2], ci = n[3] || 0;
        return [new Date(n[1]), [c - ci, c, c + ci], n[4] ? [null, null, null] : [c, c, c]];
      });
      var cps = mt.changes.map(function (c) { return { date: new Date(c.date_after), c: c }; });
      var counted = false;
      chart(sec, data, {
        labels: ["night", name, "unstable night"], customBars: true, drawPoints: true, pointSize: 3,
        series: { "unstable night": { strokeWidth: 0, pointSize: 5, color: "#d95f02" } },
        ylabel: name + (hasCi ? " (bars: 95% CI)" : ""), axes: { y: { axisLabelWidth: 70 } },
        underlayCallback: function (ctx, area, g) {
          cps.forEach(function (p) {
            var x = g.toDomXCoord(p.date.getTime() - 1);
            ctx.fillStyle = p.c.regression ? (p.c.accepted ? "rgba(120,120,120,0.5)" : "rgba(200,0,0,0.5)") : "rgba(0,130,0,0.5)";
            ctx.fillRect(x - 1, area.y, 2, area.h);
          });
          /* the notes: a dashed line on the night, its text at the top (machine changes purple, annotations blue) */
          notes.forEach(function (p, i) {
            var x = g.toDomXCoord(p.date.getTime());
            ctx.save();
            ctx.strokeStyle = ctx.fillStyle = p.n.machine ? "#7b3294" : "#2166ac";
            ctx.setLineDash([4, 3]);
            ctx.beginPath();
            ctx.moveTo(x, area.y);
            ctx.lineTo(x, area.y + area.h);
            ctx.stroke();
            ctx.font = "11px system-ui, sans-serif";
            var t = (p.n.accept ? "accepted: " : "") + p.n.text;
            if (t.length > 60) t = t.slice(0, 59) + "…";
            var w = ctx.measureText(t).width;
            ctx.fillText(t, Math.min(x + 3, area.x + area.w - w), area.y + 11 + 12 * (i % 3));
            ctx.restore();
          });
          if (!counted) { counted = true; document.body.dataset.notesDrawn = String(+(document.body.dataset.notesDrawn || 0) + notes.length); }
        }
      }, null, true);
      if (mt.changes.length) sec.appendChild(changesTable(mt.changes));
      var list = el("p", { "class": "small" }, ["nights: "]);
      mt.nights.forEach(function (n, i) { if (i) list.appendChild(document.createTextNode(" ")); list.appendChild(el("a", { href: "night.html?n=" + n[0], text: "#" + n[0] })); });
      sec.appendChild(list);
    });
    done();
  }

  return {
    start: function (k) {
      kind = k;
      if (typeof Dygraph === "undefined") { errors.push("dygraphs did not load"); return fail("The charting library (assets/dygraph.min.js) did not load."); }
      var n = param("n");
      if (k === "index") load("data/index.js");
      else if (k === "night" || k === "run") {
        if (!/^[0-9]+$/.test(n || "")) return fail("which night? (night.html?n=ID)");
        load("data/night-" + n + ".js");
        if (k === "run") load("data/frames-" + n + ".js");
      } else if (k === "front") {
        load("data/front.js");
      } else if (k === "series") {
        var s = param("s");
        if (!/^[0-9]+$/.test(s || "")) return fail("which series? (series.html?s=ID)");
        load("data/series-" + s + ".js");
      }
    },
    data: function (d) {
      got[d.kind] = d;
      if (--want > 0) return;
      try {
        if (kind === "index") pageIndex(got.index);
        else if (kind === "night") pageNight(got.night);
        else if (kind === "run") pageRun(got.night, got.frames);
        else if (kind === "series") pageSeries(got.series);
        else if (kind === "front") pageFront(got.front);
      } catch (e) {
        errors.push(String(e && e.stack || e));
        fail("report error: " + e);
      }
    }
  };
})();
