# Plots far-study's CSV: per scene (columns; the scaling family is in plot_scaling.gp), time per
# step against missed contacts (top row) and against the primitive PCS size (bottom row), contacts
# configurations only. Colour: method; point: mechanism; the points of one GPU method and
# mechanism are joined in resolution order (256 -> 2048); the bottom row labels far id-buffer's
# points with their resolution.
#   gnuplot -e "csv='study.csv'; png='study.png'" bench/study/plot_study.gp
if (!exists("csv")) csv = "study.csv"
if (!exists("png")) png = "study.png"

set datafile separator ","
set datafile columnheaders

scenes = system(sprintf("awk -F, 'NR > 1 && $2 != \"scaling\" && !seen[$1]++ { printf \"%%s \", $1 }' '%s'", csv))
nscenes = words(scenes)
set terminal pngcairo size (nscenes > 5 ? 360 * nscenes : 1800),1000 font "DejaVu Sans,11"
set output png

methods = "cullide far far-exact-offset"
mechanisms = "id-buffer occlusion-query"
colour(m) = (m eq "cullide") ? "#d62728" : (m eq "far") ? "#1f77b4" : (m eq "far-exact-offset") ? "#2ca02c" : (m eq "aabb") ? "#7f7f7f" : (m eq "bvh") ? "#9467bd" : (m eq "auto") ? "#8c564b" : (m eq "fcl") ? "#ff7f0e" : "#000000"
ptype(k) = (k eq "id-buffer") ? 7 : 5
# Contacts rows; exact is the reference, which asks for distance pairs where the distance pass runs.
here(m) = strcol("scene") eq scene && strcol("method") eq m && (strcol("output") eq "contacts" || m eq "exact")

set multiplot layout 2, nscenes title "far-study: time per step (median, log scale) against missed contacts and PCS size" font ",14"
set logscale x
set xrange [*:*]
set grid
set xlabel "time per step (ms)"

do for [row = 1:2] {
  do for [s = 1:nscenes] {
    scene = word(scenes, s)
    if (s == 1) { set key top right font ",9" samplen 2 } else { unset key }
    if (row == 1) {
      set title sprintf("%s: missed contacts (total over steps)", scene)
      set ylabel "missed contacts"
      unset logscale y
      set yrange [-0.5:5<*]
      ycol = "missed_total"
    } else {
      set title sprintf("%s: primitive PCS size (median per step)", scene)
      set ylabel "PCS triangles (+1, log)"
      set logscale y
      set yrange [*:*]
      ycol = "pcs_primitives"
    }
    plot \
      for [m in methods] for [k in mechanisms] csv \
        using ((here(m) && strcol("mechanism") eq k) ? column("step_ms_median") : NaN):(column(ycol) + (row == 2 ? 1 : 0)) \
        with linespoints lc rgb colour(m) pt ptype(k) ps 1.4 title sprintf("%s %s", m, k), \
      for [m in "aabb bvh auto fcl exact"] csv \
        using (here(m) ? column("step_ms_median") : NaN):(column(ycol) + (row == 2 ? 1 : 0)) \
        with points lc rgb colour(m) pt 9 ps 2 title m, \
      csv using ((row == 2 && here("far") && strcol("mechanism") eq "id-buffer") ? column("step_ms_median") : NaN):(column(ycol) + (row == 2 ? 1 : 0)):(sprintf("%d", column("resolution"))) \
        with labels offset 0,1 font ",8" tc rgb "#1f77b4" notitle
  }
}
unset multiplot
