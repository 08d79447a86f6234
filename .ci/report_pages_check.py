#!/usr/bin/env python3
"""Open report pages in headless Chromium and check what a reader would see
(.ci/report-pages.sh makes one page of every kind and calls this on them).

For each page (an `index.html` or a bench page), a copy beside it gets a small
script (the pages themselves carry none) that, once the page has loaded, records:
  * errors: a resource that failed to load, a script error, console.error;
  * every local link (`<a href>`, `<img src>`, and the links of the Markdown page
    beside it, which link the charts as files): the file exists and is not empty,
    and an SVG among them parses and loads as an image;
  * every chart (inline `<svg>`): it has marks (paths, lines, markers: not empty),
    every text element lies inside the chart's box (a cut-off legend or label
    does not), and no two text elements overlap (overlapping labels).
Chromium prints the page's DOM after loading (`--dump-dom`, with a virtual time
budget so that the image loads finish) and this reads the record back from it.
Exit 1 when a page fails a check, with each failure on a line of its own.

Usage: report_pages_check.py PAGE.html...
"""
import json
import os
import re
import subprocess
import sys
import tempfile

CHECK = r"""<script>
(function () {
  var errors = [];
  window.addEventListener('error', function (e) {
    var t = e.target;
    errors.push(t && t !== window ? 'failed to load: ' + (t.src || t.href) : 'script error: ' + e.message);
  }, true);
  var ce = console.error;
  console.error = function () {
    errors.push('console.error: ' + Array.prototype.join.call(arguments, ' '));
    ce.apply(console, arguments);
  };
  function local(u) { return u && !/^([a-z]+:|#|\/\/)/i.test(u); }
  function box(el) { return el.getBoundingClientRect(); }
  function overlap(a, b) {
    var w = Math.min(a.right, b.right) - Math.max(a.left, b.left);
    var h = Math.min(a.bottom, b.bottom) - Math.max(a.top, b.top);
    return w > 1.5 && h > 1.5;
  }
  window.addEventListener('load', function () {
    var out = { errors: errors, charts: [], links: [] };
    document.querySelectorAll('svg').forEach(function (svg, k) {
      if (svg.parentElement && svg.parentElement.closest('svg')) return;
      var r = box(svg);
      var texts = [];
      svg.querySelectorAll('text').forEach(function (t) {
        var b = box(t);
        if (b.width > 0 && b.height > 0 && t.textContent.trim()) texts.push([t, b]);
      });
      var outside = [], overlapping = [];
      texts.forEach(function (x) {
        var b = x[1];
        if (b.left < r.left - 1 || b.right > r.right + 1 || b.top < r.top - 1 || b.bottom > r.bottom + 1)
          outside.push('"' + x[0].textContent.trim().slice(0, 50) + '" at x ' + Math.round(b.left - r.left) +
            '..' + Math.round(b.right - r.left) + ', y ' + Math.round(b.top - r.top) + '..' +
            Math.round(b.bottom - r.top) + ' of ' + Math.round(r.width) + 'x' + Math.round(r.height));
      });
      for (var i = 0; i < texts.length; i++)
        for (var j = i + 1; j < texts.length; j++)
          if (overlap(texts[i][1], texts[j][1]))
            overlapping.push('"' + texts[i][0].textContent.trim().slice(0, 40) + '" and "' +
              texts[j][0].textContent.trim().slice(0, 40) + '"');
      out.charts.push({
        label: svg.getAttribute('aria-label') || ('chart ' + (k + 1)),
        width: r.width, height: r.height, texts: texts.length,
        marks: svg.querySelectorAll('path,polyline,polygon,circle,line,rect').length,
        outside: outside, overlapping: overlapping
      });
    });
    var urls = EXTRA.slice();
    document.querySelectorAll('a[href],img[src]').forEach(function (a) {
      var u = a.getAttribute('href') || a.getAttribute('src');
      if (local(u) && urls.indexOf(u) < 0) urls.push(u);
    });
    var pending = urls.length;
    function done() {
      var pre = document.createElement('pre');
      pre.id = 'dea-fit-check';
      pre.textContent = JSON.stringify(out);
      document.body.appendChild(pre);
    }
    if (!pending) done();
    urls.forEach(function (u) {
      var link = { url: u, ok: false, why: '' };
      out.links.push(link);
      var x = new XMLHttpRequest();
      try { x.open('GET', u, false); x.send(); } catch (e) { link.why = String(e); }
      var text = x.responseText || '';
      if (!text.length) link.why = link.why || 'missing or empty';
      var svg = /\.svg$/i.test(u.split(/[?#]/)[0]);
      if (!text.length || !svg) {
        link.ok = text.length > 0;
        if (--pending === 0) done();
        return;
      }
      var doc = new DOMParser().parseFromString(text, 'image/svg+xml');
      if (doc.getElementsByTagName('parsererror').length) {
        link.why = 'does not parse as SVG';
        if (--pending === 0) done();
        return;
      }
      var img = new Image();
      img.onload = function () {
        link.ok = img.naturalWidth > 0;
        link.why = link.ok ? '' : 'loads with no size';
        if (--pending === 0) done();
      };
      img.onerror = function () { link.why = 'does not load as an image'; if (--pending === 0) done(); };
      img.src = u;
    });
  });
})();
</script>
"""


def check(page):
    """The failures of one page (empty: it passes) and a one-line summary."""
    html = open(page, encoding="utf-8").read()
    m = re.search(r"<head[^>]*>", html, re.I)
    at = m.end() if m else 0
    md = page[: -len(".html")] + ".md"
    extra = []
    if os.path.isfile(md):
        for u in re.findall(r"\]\(([^)\s]+)\)", open(md, encoding="utf-8").read()):
            if not re.match(r"^([a-z]+:|#|//)", u, re.I) and u not in extra:
                extra.append(u)
    script = CHECK.replace("(function () {", "(function () {\n  var EXTRA = " + json.dumps(extra) + ";", 1)
    copy = os.path.join(os.path.dirname(page), ".check-" + os.path.basename(page))
    with open(copy, "w", encoding="utf-8") as f:
        f.write(html[:at] + script + html[at:])
    try:
        with tempfile.TemporaryDirectory() as profile:
            p = subprocess.run(
                [
                    "chromium", "--headless", "--no-sandbox", "--disable-gpu",
                    "--allow-file-access-from-files", "--window-size=1200,1600",
                    "--virtual-time-budget=5000", "--enable-logging=stderr", "--v=0",
                    f"--user-data-dir={profile}", "--dump-dom",
                    "file://" + os.path.abspath(copy),
                ],
                capture_output=True, text=True, timeout=60,
            )
    finally:
        os.remove(copy)
    m = re.search(r'<pre id="dea-fit-check">(.*?)</pre>', p.stdout, re.S)
    if not m:
        return [f"the check did not report (chromium exit {p.returncode}): {p.stderr[-500:]}"], ""
    import html as h
    r = json.loads(h.unescape(m.group(1)))
    fails = list(r["errors"])
    fails += [line for line in p.stderr.splitlines() if "CONSOLE" in line and "ERROR" in line.upper()]
    for l in r["links"]:
        if not l["ok"]:
            fails.append(f"link {l['url']}: {l['why']}")
    for c in r["charts"]:
        if c["marks"] < 3:
            fails.append(f"chart '{c['label']}': empty ({c['marks']} marks)")
        if c["width"] < 10 or c["height"] < 10:
            fails.append(f"chart '{c['label']}': {c['width']}x{c['height']} px")
        fails += [f"chart '{c['label']}': text outside the chart: {o}" for o in c["outside"]]
        fails += [f"chart '{c['label']}': overlapping text: {o}" for o in c["overlapping"]]
    texts = sum(c["texts"] for c in r["charts"])
    return fails, f"{len(r['charts'])} chart(s), {texts} text(s), {len(r['links'])} link(s)"


def main(pages):
    bad = 0
    for page in pages:
        fails, summary = check(page)
        if fails:
            bad += 1
            print(f"FAIL {page}: {summary}")
            for f in fails:
                print(f"  - {f}")
        else:
            print(f"ok   {page}: {summary}")
    print(f"report-pages: {len(pages) - bad} of {len(pages)} page(s) pass")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
