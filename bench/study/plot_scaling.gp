# Plots the scaling family of far-study's CSV: median time per step (contacts, log scale)
# against the scene's triangles (log scale), one line per configuration run on some size (aabb,
# bvh, auto, fcl, far/id-buffer/256 up to --scaling-gpu-max, exact up to
# --scaling-reference-max).
#   gnuplot -e "csv='study.csv'; png='study_scaling.png'" bench/study/plot_scaling.gp
if (!exists("csv")) csv = "study.csv"
if (!exists("png")) png = "study_scaling.png"

set datafile separator ","
set datafile columnheaders
set terminal pngcairo size 1200,800 font "DejaVu Sans,11"
set output png

# The configurations in the order of the CSV (columns found by name in the header); exact is the
# reference, which asks for distance pairs where the distance pass runs.
configs = system(sprintf("awk -F, 'NR == 1 { for (i = 1; i <= NF; ++i) c[$i] = i; next } $c[\"family\"] == \"scaling\" && ($c[\"output\"] == \"contacts\" || $c[\"method\"] == \"exact\") && !seen[$c[\"config\"]]++ { printf \"%%s \", $c[\"config\"] }' '%s'", csv))
n = words(configs)

# One block per configuration (two blank lines apart), so that each is one joined line.
$series << EOD
EOD
do for [i = 1:n] {
  config = word(configs, i)
  set table $series append
  plot csv using (column("triangles")):(column("step_ms_median")) with table \
    if (strcol("family") eq "scaling" && (strcol("output") eq "contacts" || strcol("method") eq "exact") && strcol("config") eq config)
  unset table
  set print $series append
  print ""
  print ""
  unset print
}

colour(m) = (m eq "aabb") ? "#7f7f7f" : (m eq "bvh") ? "#9467bd" : (m eq "auto") ? "#8c564b" : (m eq "fcl") ? "#ff7f0e" : (m eq "exact") ? "#000000" : (m[1:17] eq "far-exact-offset/") ? "#2ca02c" : (m[1:8] eq "cullide/") ? "#d62728" : "#1f77b4"
# GL configurations of one method share its colour: the mechanism and resolution tell them apart.
dashes(m) = strstrt(m, "occlusion-query") ? 2 : (strstrt(m, "/256") || strstrt(m, "/") == 0) ? 1 : 3
points(m) = strstrt(m, "occlusion-query") ? 5 : (strstrt(m, "/256") || strstrt(m, "/") == 0) ? 7 : 9
set datafile separator whitespace
set datafile nocolumnheaders
set logscale xy
set grid
set key top left
set title "far-study, scaling family: time per step against triangles (median, contacts)" font ",14"
set xlabel "triangles"
set ylabel "time per step (ms)"
plot for [i = 1:n] $series index (i - 1) using 1:2 with linespoints lw 2 pt points(word(configs, i)) dt dashes(word(configs, i)) \
  lc rgb colour(word(configs, i)) title word(configs, i)
