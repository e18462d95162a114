// Galleries: wipe or flip between the reference and the selected estimate, and show the crop
// (from the manifest, or the centre) enlarged for both; the compact table's rows open their
// scene's galleries on demand. No network, no libraries.
"use strict";
(function () {
  function initGallery(g) {
    var stage = g.querySelector(".stage");
    var ref = stage.querySelector("img.ref");
    var est = stage.querySelector("img.est");
    var divider = stage.querySelector(".divider");
    var cropbox = stage.querySelector(".cropbox");
    var tagRight = stage.querySelector(".tag.right");
    var slider = g.querySelector("input.wipe");
    var toggle = g.querySelector("button.toggle");
    var zref = g.querySelector("img.zref");
    var zest = g.querySelector("img.zest");
    var zlabel = g.querySelector(".zlabel");
    var zinfo = g.querySelector(".zinfo");
    var items = Array.prototype.slice.call(g.querySelectorAll(".thumb.item"));
    var modes = Array.prototype.slice.call(g.querySelectorAll(".modes button"));
    var mode = "wipe";
    var showingRef = false;
    var crop = null; // {x, y, w, h} in image pixels
    var spec = g.getAttribute("data-crop");
    if (spec) {
      var v = spec.split(",").map(Number);
      if (v.length === 4 && v.every(isFinite) && v[2] > 0 && v[3] > 0) {
        crop = { x: v[0], y: v[1], w: v[2], h: v[3] };
      }
    }

    function size() {
      return { w: ref.naturalWidth || 0, h: ref.naturalHeight || 0 };
    }

    // Small images are shown enlarged by a whole factor (pixels stay square), up to 560 px.
    function placeStage() {
      var s = size();
      if (!(s.w > 0)) return;
      var k = Math.max(1, Math.floor(560 / s.w));
      stage.style.width = s.w * k + "px";
    }

    function placeCrop() {
      var s = size();
      if (!(s.w > 0 && s.h > 0)) return;
      placeStage();
      if (!crop) {
        var c = Math.max(1, Math.round(Math.min(s.w, s.h) / 4));
        crop = { x: Math.floor((s.w - c) / 2), y: Math.floor((s.h - c) / 2), w: c, h: c };
      }
      crop.w = Math.min(crop.w, s.w);
      crop.h = Math.min(crop.h, s.h);
      crop.x = Math.max(0, Math.min(crop.x, s.w - crop.w));
      crop.y = Math.max(0, Math.min(crop.y, s.h - crop.h));
      cropbox.style.left = (100 * crop.x) / s.w + "%";
      cropbox.style.top = (100 * crop.y) / s.h + "%";
      cropbox.style.width = (100 * crop.w) / s.w + "%";
      cropbox.style.height = (100 * crop.h) / s.h + "%";
      var box = 240;
      var scale = Math.max(1, Math.floor(box / Math.max(crop.w, crop.h)));
      [zref, zest].forEach(function (img) {
        var frame = img.parentNode;
        frame.style.width = crop.w * scale + "px";
        frame.style.height = crop.h * scale + "px";
        img.style.width = s.w * scale + "px";
        img.style.height = s.h * scale + "px";
        img.style.left = -crop.x * scale + "px";
        img.style.top = -crop.y * scale + "px";
      });
      zinfo.textContent =
        crop.w + "×" + crop.h + " px at (" + crop.x + ", " + crop.y + "), enlarged ×" + scale;
    }

    function update() {
      g.classList.toggle("flip", mode === "flip");
      slider.hidden = mode !== "wipe";
      toggle.hidden = mode !== "flip";
      modes.forEach(function (b) {
        b.classList.toggle("on", b.getAttribute("data-mode") === mode);
      });
      if (mode === "wipe") {
        var p = Number(slider.value);
        est.style.visibility = "visible";
        est.style.clipPath = "inset(0 0 0 " + p + "%)";
        divider.style.left = p + "%";
        tagRight.style.visibility = p < 95 ? "visible" : "hidden";
      } else {
        est.style.clipPath = "none";
        est.style.visibility = showingRef ? "hidden" : "visible";
        tagRight.textContent = showingRef ? ref.alt : est.alt;
        toggle.textContent = showingRef ? "Show estimate" : "Show reference";
        tagRight.style.visibility = "visible";
      }
    }

    function select(button) {
      items.forEach(function (b) {
        b.classList.toggle("on", b === button);
      });
      var src = button.getAttribute("data-src");
      var label = button.getAttribute("data-label");
      est.src = src;
      est.alt = label;
      zest.src = src;
      zest.alt = label + " crop";
      zlabel.textContent = label;
      tagRight.textContent = label;
      showingRef = false;
      update();
    }

    function flip() {
      if (mode !== "flip") mode = "flip";
      else showingRef = !showingRef;
      update();
    }

    function wipeTo(event) {
      var r = stage.getBoundingClientRect();
      if (!(r.width > 0)) return;
      slider.value = Math.max(0, Math.min(100, (100 * (event.clientX - r.left)) / r.width));
      update();
    }

    function moveCrop(event) {
      var s = size();
      var r = stage.getBoundingClientRect();
      if (!crop || !(r.width > 0) || !(s.w > 0)) return;
      var px = ((event.clientX - r.left) / r.width) * s.w;
      var py = ((event.clientY - r.top) / r.height) * s.h;
      crop.x = Math.round(px - crop.w / 2);
      crop.y = Math.round(py - crop.h / 2);
      placeCrop();
    }

    // Halve or double the crop about its centre (at least 4 pixels, at most the image).
    function resizeCrop(f) {
      var s = size();
      if (!crop || !(s.w > 0)) return;
      var cx = crop.x + crop.w / 2;
      var cy = crop.y + crop.h / 2;
      crop.w = Math.max(4, Math.min(s.w, Math.round(crop.w * f)));
      crop.h = Math.max(4, Math.min(s.h, Math.round(crop.h * f)));
      crop.x = Math.round(cx - crop.w / 2);
      crop.y = Math.round(cy - crop.h / 2);
      placeCrop();
    }
    Array.prototype.forEach.call(g.querySelectorAll("button.zsize"), function (b) {
      b.addEventListener("click", function () {
        resizeCrop(Number(b.getAttribute("data-f")));
      });
    });

    var dragging = false;
    var moved = false;
    stage.addEventListener("pointerdown", function (e) {
      dragging = true;
      moved = false;
      if (stage.setPointerCapture) stage.setPointerCapture(e.pointerId);
    });
    stage.addEventListener("pointermove", function (e) {
      if (dragging && mode === "wipe") {
        moved = true;
        wipeTo(e);
      }
    });
    stage.addEventListener("pointerup", function (e) {
      dragging = false;
      if (!moved) {
        if (mode === "flip" && !e.shiftKey) flip();
        else moveCrop(e);
      }
    });
    stage.addEventListener("dblclick", moveCrop);
    slider.addEventListener("input", update);
    toggle.addEventListener("click", flip);
    modes.forEach(function (b) {
      b.addEventListener("click", function () {
        mode = b.getAttribute("data-mode");
        showingRef = false;
        update();
      });
    });
    items.forEach(function (b) {
      b.addEventListener("click", function () {
        select(b);
      });
    });
    g.addEventListener("keydown", function (e) {
      if (e.key === "f" || e.key === "F") {
        e.preventDefault();
        flip();
      } else if ((e.key === "ArrowRight" || e.key === "ArrowLeft") && items.length > 1) {
        var i = items.findIndex(function (b) {
          return b.classList.contains("on");
        });
        var n = items.length;
        select(items[(i + (e.key === "ArrowRight" ? 1 : n - 1)) % n]);
        e.preventDefault();
      }
    });
    if (ref.complete) placeCrop();
    ref.addEventListener("load", placeCrop);
    update();

    // Every control once, for the browser test (index.html#exercise).
    return function exercise() {
      items.forEach(select);
      mode = "flip";
      update();
      flip();
      flip();
      mode = "wipe";
      slider.value = 25;
      update();
      var r = stage.getBoundingClientRect();
      moveCrop({ clientX: r.left + r.width / 3, clientY: r.top + r.height / 3 });
      resizeCrop(0.5);
      resizeCrop(2);
      if (items.length) select(items[0]);
    };
  }

  var exercises = Array.prototype.map.call(document.querySelectorAll(".gallery"), initGallery);

  // The compact table's rows: a click shows the row's detail and, the first time, puts in its
  // scene's full-size galleries if their reference loads (they are not committed); otherwise
  // the detail's line says how to make them. Resolves once the row has settled.
  function toggleRow(row) {
    var detail = row.nextElementSibling;
    var opening = detail.hidden;
    detail.hidden = !opening;
    row.setAttribute("aria-expanded", String(opening));
    var tpl = detail.querySelector("template");
    if (!opening || !tpl || detail.getAttribute("data-state")) return Promise.resolve();
    detail.setAttribute("data-state", "probing");
    return new Promise(function (resolve) {
      var probe = new Image();
      probe.onload = function () {
        var box = detail.querySelector(".opened");
        box.appendChild(tpl.content.cloneNode(true));
        Array.prototype.forEach.call(box.querySelectorAll(".gallery"), function (g) {
          exercises.push(initGallery(g));
        });
        detail.setAttribute("data-state", "shown");
        resolve();
      };
      probe.onerror = function () {
        detail.setAttribute("data-state", "absent");
        resolve();
      };
      probe.src = tpl.getAttribute("data-probe");
    });
  }
  var rows = Array.prototype.slice.call(document.querySelectorAll("tr.scene"));
  rows.forEach(function (row) {
    row.addEventListener("click", function () {
      toggleRow(row);
    });
    row.addEventListener("keydown", function (e) {
      if (e.key === "Enter" || e.key === " ") {
        e.preventDefault();
        toggleRow(row);
      }
    });
  });

  // Every row opened, then every gallery's controls driven (index.html#exercise).
  window.ltExercise = function () {
    return Promise.all(rows.map(toggleRow)).then(function () {
      exercises.forEach(function (f) {
        f();
      });
      document.body.setAttribute("data-exercised", "1");
    });
  };
})();
