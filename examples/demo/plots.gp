# Demo plots from haptic-server's per-tick trace (columns: see
# haptics/include/haptics/trace.hpp). Called by scripts/demo:
#   gnuplot -e "trace='demo-out/trace.csv'; outdir='demo-out'; fscale=0.6; fsign=1; pscale=1" examples/demo/plots.gp
# fscale / fsign / pscale: force scale and sign and position scale of the
# pressing joint (master N m per slave N m, slave rad per master rad), so the
# stiffness plot shows what the surgeon feels in the same units as the truth.
set datafile separator ","
# noenhanced: labels print as written (tau_in, not a subscript); the legend
# sits below the plot, never on the data.
set terminal pngcairo size 1200,760 noenhanced font ",11"
set key below horizontal
set grid
# Column of field k (1-based within a joint block of 11) for joint j.
col(j, k) = 5 + j * 11 + k

do for [j = 0:1] {
  set output sprintf("%s/torque-joint%d.png", outdir, j)
  set title sprintf("Joint %d: distal torque fed back vs the truth", j)
  set xlabel "time (s)"
  set ylabel "distal torque (N m)"
  plot trace using 1:(column(col(j, 8))) every 5 with lines lw 2 lc rgb "black" title "true distal torque", \
       trace using 1:(column(col(j, 3))) every 5 with lines lc rgb "#d62728" title "naive (proximal tau_in)", \
       trace using 1:(column(col(j, 4))) every 5 with lines lc rgb "#1f77b4" title "estimated (friction model)"
}

if (!exists("fscale")) fscale = 1.0
if (!exists("fsign")) fsign = 1.0
if (!exists("pscale")) pscale = 1.0
set output sprintf("%s/stiffness.png", outdir)
# The master renders the reaction, -fsign x fscale x tau: divided by that,
# the rendered torque reads as the slave torque it stands for.
set title sprintf("What the surgeon feels, in slave joint units (master torque / %g, master angle x %g), pressing joint 0", -fsign * fscale, pscale)
set xlabel "joint angle (rad): master angle x position scale, or the true joint angle"
set ylabel "torque (N m, slave joint)"
plot trace using (column(col(0, 1)) * pscale):(column(col(0, 5)) / (-fsign * fscale)) every 3 with points pt 7 ps 0.3 lc rgb "#1f77b4" title "rendered reaction / (-force sign x force scale) vs master angle x position scale", \
     trace using (column(col(0, 9))):(column(col(0, 8))) every 3 with points pt 7 ps 0.3 lc rgb "black" title "true distal torque vs true joint angle"
