//! The report page's style sheet and its script (filter buttons and the
//! search box; the page works without it).

pub const STYLE: &str = r#"
:root { --pass:#1a7f37; --pass-bg:#eaf6ec; --fail:#cf222e; --fail-bg:#fdecea; --err:#a3440b;
        --err-bg:#fff0e0; --noref:#656d76; --line:#d8dee4; --muted:#57606a; }
* { box-sizing: border-box; }
body { font: 14px/1.45 system-ui, -apple-system, "Segoe UI", Roboto, sans-serif; color:#1f2328;
       margin: 0; padding: 20px 28px 40px; background:#fff; }
h1 { font-size: 22px; margin: 0 0 4px; }
h2 { font-size: 15px; margin: 22px 0 8px; }
.meta { color: var(--muted); margin: 0 0 16px; }
code, pre { font-family: ui-monospace, SFMono-Regular, Menlo, Consolas, monospace; font-size: 12px; }
.cards { display: flex; gap: 12px; flex-wrap: wrap; }
.card { border: 1px solid var(--line); border-left-width: 6px; border-radius: 6px; padding: 8px 16px;
        min-width: 130px; }
.card b { display: block; font-size: 26px; line-height: 1.1; }
.card.pass { border-left-color: var(--pass); } .card.pass b { color: var(--pass); }
.card.fail { border-left-color: var(--fail); } .card.fail b { color: var(--fail); }
.card.error { border-left-color: var(--err); } .card.error b { color: var(--err); }
.card.noref { border-left-color: var(--noref); } .card.time { border-left-color: #0969da; }
table { border-collapse: collapse; }
table.hw td, table.hw th { padding: 3px 12px; border-bottom: 1px solid var(--line); text-align: right; }
table.hw td:first-child, table.hw th:first-child { text-align: left; }
table.hw tfoot td { font-weight: 600; border-bottom: none; }
.n-pass { color: var(--pass); } .n-fail { color: var(--fail); font-weight: 600; }
.n-error { color: var(--err); font-weight: 600; } .zero { color: #adb5bd; font-weight: normal; }
.bar { display: inline-flex; width: 160px; height: 10px; border-radius: 3px; overflow: hidden;
       background: #eef1f4; vertical-align: middle; }
.bar span { display: block; height: 100%; }
.bar .p { background: var(--pass); } .bar .f { background: var(--fail); } .bar .e { background: var(--err); }
.filters { margin: 20px 0 10px; display: flex; gap: 8px; align-items: center; flex-wrap: wrap; }
.filters button { font: inherit; padding: 4px 12px; border: 1px solid var(--line); border-radius: 16px;
                  background: #f6f8fa; cursor: pointer; }
.filters button.on { background: #1f2328; color: #fff; border-color: #1f2328; }
.filters input { font: inherit; padding: 4px 10px; border: 1px solid var(--line); border-radius: 6px;
                 width: 300px; margin-left: 8px; }
table.results { width: 100%; }
table.results th { position: sticky; top: 0; background: #f6f8fa; z-index: 1; text-align: left;
                   font-weight: 600; padding: 6px 6px; border-bottom: 2px solid var(--line); white-space: nowrap; }
table.results td { padding: 6px 6px; border-bottom: 1px solid var(--line); vertical-align: top; }
table.results td.num { text-align: right; white-space: nowrap; font-variant-numeric: tabular-nums; }
tr.row { border-left: 6px solid transparent; }
tr.row.fail { background: var(--fail-bg); border-left-color: var(--fail); }
tr.row.error { background: var(--err-bg); border-left-color: var(--err); }
tr.row.pass { border-left-color: var(--pass); }
tr.row.no-reference, tr.row.unsupported, tr.row.known-quirk { border-left-color: var(--noref); }
tr.first td { border-top: 1px solid #afb8c1; }
td.scene { min-width: 210px; max-width: 260px; overflow-wrap: break-word; }
td.scene .dir { display: block; color: var(--muted); font-size: 12px; }
td.scene .label { font-weight: 600; }
td.scene .image { display: block; margin-top: 2px; font-size: 12px; }
.enc { display: inline-block; font-size: 11px; padding: 0 6px; border-radius: 8px; background: #ddf4ff;
       color: #0550ae; margin-left: 4px; }
.enc.xml { background: #fbefff; color: #8250df; }
details { margin-top: 4px; color: var(--muted); font-size: 12px; }
details summary { cursor: pointer; }
details ul { margin: 4px 0 0; padding-left: 18px; max-height: 220px; overflow: auto; }
td.img { width: 124px; }
td.img img { width: 112px; display: block; border: 1px solid var(--line); background: #f6f8fa;
             image-rendering: auto; }
td.img img.hdr { margin-top: 6px; }
td.img .none { display: block; width: 112px; color: #adb5bd; font-size: 12px; text-align: center;
               padding: 30px 0; border: 1px dashed var(--line); }
.bad { color: var(--fail); font-weight: 700; }
.sub { display: block; color: var(--muted); font-size: 11px; }
.sub.bad { color: var(--fail); }
.thr { text-decoration: underline dotted; cursor: help; white-space: nowrap; font-size: 11px; }
.verdict { display: inline-block; font-weight: 700; font-size: 12px; padding: 2px 8px; border-radius: 10px;
           color: #fff; white-space: nowrap; }
.verdict.pass { background: var(--pass); } .verdict.fail { background: var(--fail); }
.verdict.error { background: var(--err); } .verdict.no-reference { background: var(--noref); }
.verdict.unsupported, .verdict.known-quirk { background: var(--noref); }
pre.err { white-space: pre-wrap; word-break: break-word; margin: 0; color: #82071e; max-width: 640px; }
.note { color: var(--err); font-size: 12px; margin-top: 4px; }
footer { margin-top: 24px; color: var(--muted); font-size: 12px; }
"#;

pub const SCRIPT: &str = r#"
(function () {
  var rows = Array.prototype.slice.call(document.querySelectorAll('tr.row'));
  var buttons = Array.prototype.slice.call(document.querySelectorAll('.filters button'));
  var search = document.getElementById('search');
  var filter = 'all';
  function apply() {
    var q = search.value.trim().toLowerCase();
    rows.forEach(function (r) {
      var v = r.getAttribute('data-verdict');
      var ok = filter === 'all' || (filter === 'problems' && (v === 'fail' || v === 'error')) || filter === v;
      r.hidden = !(ok && (!q || r.getAttribute('data-label').indexOf(q) >= 0));
    });
  }
  buttons.forEach(function (b) {
    b.addEventListener('click', function () {
      filter = b.getAttribute('data-filter');
      buttons.forEach(function (o) { o.classList.toggle('on', o === b); });
      apply();
    });
  });
  search.addEventListener('input', apply);
  Array.prototype.slice.call(document.querySelectorAll('a[data-q]')).forEach(function (a) {
    a.addEventListener('click', function (e) { e.preventDefault(); search.value = a.getAttribute('data-q'); apply(); });
  });
})();
"#;
