# Plot of bench_teleop_delay's runs (scripts/bench-delay):
#   gnuplot -e "dir='bench-delay-out'" tests/haptics/bench_teleop_delay.gp
# One panel per round-trip delay: the rendered torque of the pressing joint
# with the passivity controller off and on, and the observed energy W_M.
set datafile separator ","
set terminal pngcairo size 1400,1000 noenhanced font ",10"
set output dir."/delay.png"
set multiplot layout 4,1 title "Press into the nodule and hold: rendered torque (N m), passivity off / on; W_M (J, right axis)"
set grid
set key right top horizontal
set xrange [0:7.8]
set yrange [-0.35:0.25]
set y2range [-0.06:0.06]
set y2tics
set ylabel "torque (N m)"
do for [rtt in "0 10 50 100"] {
  set title sprintf("round trip %s ms (20 %% jitter, 1 %% loss each way)", rtt)
  if (rtt eq "100") { set xlabel "time (s)" }
  plot dir."/delay-".rtt."-off.csv" using 1:3 with lines lw 1 title "torque, off", \
       dir."/delay-".rtt."-on.csv" using 1:3 with lines lw 1.5 title "torque, on", \
       dir."/delay-".rtt."-off.csv" using 1:4 axes x1y2 with lines dt 2 title "W_M, off", \
       dir."/delay-".rtt."-on.csv" using 1:4 axes x1y2 with lines dt 3 title "W_M, on"
}
unset multiplot
