"""truss_report.page.style: the report's stylesheet, for the screen and for print (A4, WeasyPrint)."""

CSS = """
body { font-family: "DejaVu Sans", Arial, sans-serif; font-size: 14px; margin: 24px auto;
       max-width: 1400px; color: #222; padding: 0 16px; }
h1 { font-size: 24px; margin-bottom: 4px; } h2 { border-bottom: 2px solid #345; margin-top: 36px; }
h3 { margin-top: 24px; } .meta { color: #555; font-size: 12px; }
nav { background: #eef2f6; padding: 6px 10px; margin: 12px 0; }
table { border-collapse: collapse; margin: 8px 0 14px 0; font-size: 13px; }
th, td { border: 1px solid #c8cdd3; padding: 3px 8px; text-align: left; vertical-align: top; }
thead th { background: #e6ebf0; } table.kv th { background: #f3f5f7; width: 380px; }
td.num { text-align: right; font-variant-numeric: tabular-nums; white-space: nowrap; }
td.toosmall { color: #8a5a00; } table.corr td.num { min-width: 70px; }
figure { margin: 8px 0 16px 0; } figure img { max-width: 100%; border: 1px solid #ddd; }
figure.half img { max-width: 100%; } figcaption { font-size: 12px; color: #555; }
.flex { display: flex; flex-wrap: wrap; gap: 0 18px; align-items: flex-start; }
.grid { display: grid; grid-template-columns: 1fr 1fr; gap: 12px 24px; }
.note { color: #555; font-style: italic; }
.warn { background: #fde8e8; border: 1px solid #d33; padding: 8px; }
.okc { color: #176b17; font-weight: bold; } .bad { color: #c00; font-weight: bold; }
pre { background: #f6f8fa; padding: 8px; font-size: 12px; overflow-x: auto; }
details { margin: 6px 0 12px 0; } summary { cursor: pointer; color: #234; }
.verdict { padding: 8px 12px; margin: 8px 0; border-radius: 4px; font-size: 14px; }
.verdict ul { margin: 4px 0 4px 18px; padding: 0; } .small { font-size: 11px; color: #444; }
.verdict.fail { background: #fde8e8; border: 2px solid #c00; }
.verdict.pass { background: #e7f6e7; border: 2px solid #176b17; }
.verdict.not_assessed { background: #fff4d6; border: 2px solid #b37400; }
table.document th { background: #f3f5f7; width: 200px; } table.document td { word-break: break-all; }
.dash { font-size: 11px; color: #444; }
table.design td, table.design th { font-size: 12px; } table.design td small { color: #555; }
h2#design, h2#mechanism { margin-top: 14px; }
table.signoff td { min-width: 180px; height: 36px; }
@media print { table.signoff { width: 100%; } table.signoff td { height: 14mm; } }
@media print {
  body { font-size: 10pt; max-width: none; margin: 0; padding: 0; }
  nav, details > summary { display: none; } details { display: block; }
  h2 { page-break-after: avoid; } figure, table, .verdict { page-break-inside: avoid; }
  figure img { max-width: 100%; border: none; } a { color: inherit; text-decoration: none; }
  .grid { display: block; } table { font-size: 8pt; } table.design td, table.design th { font-size: 7pt; }
  td.num { white-space: normal; } pre { white-space: pre-wrap; font-size: 7pt; }
  /* Every table fits the page: fixed layout at the text width, long words and numbers wrap. */
  table { width: 100%; table-layout: fixed; } th, td { overflow-wrap: anywhere; }
  table.kv th, table.document th { width: 42%; } table.signoff th { width: 16%; }
  .flex { display: block; } .flex > table { width: 70%; }
  table { page-break-inside: auto; } tr { page-break-inside: avoid; }
  h2, h3, h4 { break-after: avoid; page-break-after: avoid; }
  figure img { max-height: 215mm; width: auto; }   /* a figure, its heading and caption: one page */
  #sweep figure img { max-width: 66%; }
  #sweep table { font-size: 7pt; } #sweep td.num { white-space: nowrap; }
}
@page { size: A4; margin: 15mm 12mm 18mm 12mm;   /* the footer in the body's font: no serif font to embed */
        font-family: "DejaVu Sans", Arial, sans-serif;
        @bottom-left { content: string(doctitle); font-size: 8pt; color: #555; }
        @bottom-right { content: "page " counter(page) " of " counter(pages); font-size: 8pt;
                        color: #555; } }
h1 { string-set: doctitle content(); }
"""
