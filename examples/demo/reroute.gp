# The re-route demo's plot, from haptic-server's trace and the
# phases reroute_report.py found. Called by scripts/demo --reroute:
#   gnuplot -e "trace='DIR/trace.csv'; phases='DIR/reroute-phases.dat'; outdir='DIR'" examples/demo/reroute.gp
set datafile separator ","
set terminal pngcairo size 1200,900 noenhanced font ",11"
set key below horizontal
set grid
col(j, k) = 5 + j * 11 + k
set datafile separator whitespace
stats phases using 1 nooutput
t_reroute = STATS_min
stats phases using 2 nooutput
t_alarm = STATS_min
stats phases using 3 nooutput
t_applied = STATS_min
set datafile separator ","
stats trace using 1 nooutput
set xrange [STATS_min:STATS_max]
set output sprintf("%s/reroute.png", outdir)
set multiplot layout 2,1 title "Re-routing the sheaths (+50 % wrap), the drift alarm and the recalibration (joint1)"
set arrow 1 from t_reroute, graph 0 to t_reroute, graph 1 nohead lc rgb "black" dt 2
set label 1 "re-route" at t_reroute, graph 0.95 offset 0.5,0
set arrow 2 from t_alarm, graph 0 to t_alarm, graph 1 nohead lc rgb "#ff7f0e" dt 2
set label 2 "drift alarm" at t_alarm, graph 0.85 offset 0.5,0
set arrow 3 from t_applied, graph 0 to t_applied, graph 1 nohead lc rgb "#2ca02c" dt 2
set label 3 "recalibrated" at t_applied, graph 0.75 offset 0.5,0
set ylabel "distal torque (N m)"
plot trace using 1:(column(col(0, 8))) every 5 with lines lw 2 lc rgb "black" title "true distal torque", \
     trace using 1:(column(col(0, 4))) every 5 with lines lc rgb "#1f77b4" title "estimated (friction model, scale recalibrated)"
set xlabel "time (s)"
set ylabel "estimate - truth (N m)"
plot trace using 1:(column(col(0, 4)) - column(col(0, 8))) every 5 with lines lc rgb "#d62728" title "distal-torque error"
unset multiplot
