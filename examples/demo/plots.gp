# Demo plots from haptic-server's per-tick trace (columns: see
# haptics/include/haptics/trace.hpp). Called by scripts/demo:
#   gnuplot -e "trace='demo-out/trace.csv'; outdir='demo-out'" examples/demo/plots.gp
set datafile separator ","
set terminal pngcairo size 1200,700 font ",11"
set key top left
set grid
# Column of field k (1-based within a joint block of 11) for joint j.
col(j, k) = 5 + j * 11 + k

do for [j = 0:1] {
  set output sprintf("%s/torque-joint%d.png", outdir, j)
  set title sprintf("Joint %d: distal torque fed back vs the truth", j)
  set xlabel "time (s)"
  set ylabel "distal torque (N m)"
  plot trace using 1:(column(col(j, 8))) every 5 with lines lw 2 lc rgb "black" title "true distal torque", \
       trace using 1:(column(col(j, 3))) every 5 with lines lc rgb "#d62728" title "naive (proximal tau_{in})", \
       trace using 1:(column(col(j, 4))) every 5 with lines lc rgb "#1f77b4" title "estimated (friction model)"
}

set output sprintf("%s/stiffness.png", outdir)
set title "What the surgeon feels: master torque vs master angle, pressing joint 0"
set xlabel "master angle (rad)"
set ylabel "torque on the master (N m)"
plot trace using (column(col(0, 1))):(column(col(0, 5))) every 3 with points pt 7 ps 0.3 lc rgb "#1f77b4" title "rendered", \
     trace using (column(col(0, 1))):(column(col(0, 8))) every 3 with points pt 7 ps 0.3 lc rgb "black" title "true distal torque"
