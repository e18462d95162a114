// Self-check, read by tests/report_browser.rs from the dumped DOM: counts window errors,
// unhandled rejections and console.error calls, waits for every <img>, and writes
// {"done", "errors", "messages", "images", "broken", "broken_src"} into #lt-selfcheck.
// A broken image is one with naturalWidth 0 once it has settled (failed to load or decode).
"use strict";
(function () {
  var messages = [];
  function note(kind, text) {
    messages.push(kind + ": " + String(text));
  }
  window.addEventListener(
    "error",
    function (e) {
      // A resource that failed (an <img>) is counted as broken below, not here.
      if (e.target && e.target !== window && e.target.tagName) return;
      note("error", (e.message || "?") + " at " + (e.filename || "?") + ":" + (e.lineno || 0));
    },
    true
  );
  window.addEventListener("unhandledrejection", function (e) {
    var r = e.reason;
    note("unhandledrejection", r && (r.stack || r.message) ? r.stack || r.message : r);
  });
  var consoleError = console.error;
  console.error = function () {
    note("console.error", Array.prototype.map.call(arguments, String).join(" "));
    return consoleError.apply(console, arguments);
  };

  function settled(img) {
    return new Promise(function (resolve) {
      if (img.complete) return resolve();
      img.addEventListener("load", resolve, { once: true });
      img.addEventListener("error", resolve, { once: true });
    });
  }

  function write(done) {
    var imgs = Array.prototype.slice.call(document.images);
    var broken = imgs.filter(function (i) {
      return !(i.naturalWidth > 0);
    });
    var out = {
      done: done,
      errors: messages.length,
      messages: messages.slice(0, 20),
      images: imgs.length,
      broken: broken.length,
      broken_src: broken.slice(0, 20).map(function (i) {
        return i.getAttribute("src");
      }),
    };
    var el = document.getElementById("lt-selfcheck");
    if (el) el.textContent = JSON.stringify(out);
  }

  window.addEventListener("load", function () {
    var timer = setTimeout(function () {
      write(false);
    }, 8000);
    function allSettled() {
      return Promise.all(Array.prototype.slice.call(document.images).map(settled));
    }
    allSettled()
      .then(function () {
        // index.html#exercise: drive the galleries' controls, then wait for what they load.
        if (location.hash === "#exercise" && window.ltExercise) {
          return Promise.resolve(window.ltExercise()).then(allSettled);
        }
      })
      .catch(function (e) {
        note("exercise", e && (e.stack || e.message) ? e.stack || e.message : e);
      })
      .then(function () {
        clearTimeout(timer);
        // After the page's own load handlers have run.
        setTimeout(function () {
          write(true);
        }, 0);
      });
  });
})();
