//! The report's stylesheet: screen layout, and print rules that keep tables and figures whole on A4.

pub(super) const CSS: &str = "
body{font-family:Helvetica,Arial,sans-serif;max-width:1120px;margin:1.5em auto;color:#111;font-size:14px;line-height:1.35}
h1{font-size:24px;margin:0 0 .3em} h2{font-size:19px;border-bottom:2px solid #333;padding-bottom:2px;margin-top:1.6em}
h3{font-size:16px;margin:1.2em 0 .3em}
table{border-collapse:collapse;margin:.4em 0 1.2em}
td,th{border:1px solid #999;padding:3px 8px;text-align:right;vertical-align:top}
th{background:#eee} td.l,th.l{text-align:left} caption{text-align:left;font-weight:bold;padding:4px 0}
tr.stat td{background:#f6f6f6}
.banner{font-size:30px;font-weight:bold;padding:14px 20px;border:4px solid;margin:.6em 0 1em}
.banner small{display:block;font-size:14px;font-weight:normal;margin-top:4px}
.b-pass{color:#005a32;border-color:#005a32;background:#e5f5e0}
.b-fail{color:#a50f15;border-color:#a50f15;background:#fee0d2}
.b-und{color:#7a4b00;border-color:#b07000;background:#fff3d6}
.b-none{color:#333;border-color:#777;background:#f0f0f0}
.warn{color:#a50f15;font-weight:bold}
.pass{color:#005a32;font-weight:bold} .fail{color:#a50f15;font-weight:bold} .und{color:#7a4b00;font-weight:bold}
.meta{color:#444} svg{max-width:100%;height:auto;display:block;margin:.5em 0}
.sign table{width:100%} .sign td{height:2.6em;text-align:left;width:25%}
.small{font-size:12px;color:#444}
@page{size:A4;margin:14mm}
@media print{body{max-width:none;margin:0;font-size:11px} h2{break-after:avoid} table,svg,.banner,.sign{break-inside:avoid}
 .banner,th,tr.stat td,.b-pass,.b-fail,.b-und{-webkit-print-color-adjust:exact;print-color-adjust:exact}}
";
