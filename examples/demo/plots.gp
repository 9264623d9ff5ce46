# Demo plots from haptic-server's per-tick trace (columns: see
# haptics/include/haptics/trace.hpp). Called by scripts/demo:
#   gnuplot -e "trace='demo-out/trace.csv'; outdir='demo-out'; fscale=0.6; fsign=1; pscale=1; brake=0.02" examples/demo/plots.gp
# fscale / fsign / pscale: force scale and sign and position scale of the
# pressing joint (master N m per slave N m, slave rad per master rad), so the
# stiffness plot shows what the surgeon feels in the same units as the truth;
# brake: the passivity controller's max_brake_nm (N m on the master).
set datafile separator ","
# noenhanced: labels print as written (tau_in, not a subscript); the legend
# sits below the plot, never on the data.
set terminal pngcairo size 1200,760 noenhanced font ",11"
set key below horizontal
set grid
# Column of field k (1-based within a joint block of 11) for joint j.
col(j, k) = 5 + j * 11 + k
# The time axis ends where the data end (gnuplot would round it up to the
# next tick: 25 s for 22 s of data).
stats trace using 1 nooutput
t_first = STATS_min
t_last = STATS_max

do for [j = 0:1] {
  set output sprintf("%s/torque-joint%d.png", outdir, j + 1)
  set title sprintf("joint%d: distal torque fed back vs the truth", j + 1)
  set xlabel "time (s)"
  set ylabel "distal torque (N m)"
  set xrange [t_first:t_last]
  plot trace using 1:(column(col(j, 8))) every 5 with lines lw 2 lc rgb "black" title "true distal torque", \
       trace using 1:(column(col(j, 3))) every 5 with lines lc rgb "#d62728" title "naive (proximal tau_in)", \
       trace using 1:(column(col(j, 4))) every 5 with lines lc rgb "#1f77b4" title "estimated (friction model)"
}

if (!exists("fscale")) fscale = 1.0
if (!exists("fsign")) fsign = 1.0
if (!exists("pscale")) pscale = 1.0
set output sprintf("%s/stiffness.png", outdir)
set autoscale x
# The master renders the reaction, -fsign x fscale x tau: divided by that,
# the rendered torque reads as the slave torque it stands for.
set title sprintf("What the surgeon feels, in slave joint units (master torque / %g, master angle x %g), pressing joint1", -fsign * fscale, pscale)
set xlabel "joint angle (rad): master angle x position scale, or the true joint angle"
set ylabel "torque (N m, slave joint)"
# The rendered torque in slave units, split three ways, each with its legend:
# the tissue's reaction (in contact), free motion (out of contact: the
# phantom torque), and the passivity controller's brake: as the hand
# retreats the controller repays the energy it withheld, holding up to
# max_brake_nm against the hand (torque toward the tissue, the flat runs at
# -max_brake_nm / force scale). A torque toward the tissue beyond half that
# cap is the brake's; nothing else renders one.
if (!exists("brake")) brake = 0.02
rendered(j) = column(col(j, 5)) / (-fsign * fscale)
is_brake(j) = rendered(j) < -0.5 * brake / fscale
in_contact(j) = column(col(j, 10)) > 0 && !is_brake(j) ? 1 : NaN
out_of_contact(j) = column(col(j, 10)) == 0 && !is_brake(j) ? 1 : NaN  # NaN: no truth matched
braking(j) = is_brake(j) ? 1 : NaN
plot trace using (column(col(0, 1)) * pscale):(in_contact(0) * rendered(0)) every 3 with points pt 7 ps 0.3 lc rgb "#1f77b4" title "in contact: rendered reaction / (-force sign x force scale) vs master angle x position scale", \
     trace using (column(col(0, 1)) * pscale):(out_of_contact(0) * rendered(0)) every 3 with points pt 7 ps 0.3 lc rgb "#ff7f0e" title "out of contact: phantom torque, same scaling", \
     trace using (column(col(0, 1)) * pscale):(braking(0) * rendered(0)) every 3 with points pt 7 ps 0.3 lc rgb "#d62728" title sprintf("passivity brake: held against the retreating hand, up to max_brake_nm %g N m (%.3g N m here)", brake, -brake / fscale), \
     trace using (column(col(0, 9))):(column(col(0, 8))) every 3 with points pt 7 ps 0.3 lc rgb "black" title "true distal torque vs true joint angle"
