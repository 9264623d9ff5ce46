// lcm-spy decodes authenticated traffic (docs/bridge.md, "Authentication"):
// a message followed by the 64-byte MAC trailer decodes, through the
// DataInput constructor lcm-spy uses, to the same fields as without it.
import java.io.ByteArrayOutputStream;
import java.io.DataInput;
import java.io.DataOutputStream;
import lcm.lcm.LCMDataInputStream;

public class SignedDecode {
  public static void main(String[] args) throws Exception {
    tsmh.slave_state_t s = new tsmh.slave_state_t();
    s.num_joints = 2;
    s.seq = 42;
    s.utime = 7;
    s.x_in = new double[] {0.5, -0.25};
    s.x_out = new double[] {0.1, 0.2};
    s.T1 = new double[] {30, 31};
    s.T3 = new double[] {20, 21};
    s.radius_m = new double[] {0.01, 0.01};
    ByteArrayOutputStream bo = new ByteArrayOutputStream();
    s.encode(new DataOutputStream(bo));
    byte[] payload = bo.toByteArray();
    byte[] signed = new byte[payload.length + 64];
    System.arraycopy(payload, 0, signed, 0, payload.length);
    byte[] magic = {'T', 'S', 'M', 'A', 1};
    System.arraycopy(magic, 0, signed, payload.length, magic.length);
    for (int i = 8; i < 64; ++i) signed[payload.length + i] = (byte) (i * 37);
    tsmh.slave_state_t d =
        (tsmh.slave_state_t)
            tsmh.slave_state_t.class
                .getConstructor(DataInput.class)
                .newInstance(new LCMDataInputStream(signed, 0, signed.length));
    if (d.seq != 42 || d.num_joints != 2 || d.x_in[1] != -0.25 || d.radius_m[1] != 0.01) {
      System.out.println("FAIL: decoded seq " + d.seq + " x_in[1] " + d.x_in[1]);
      System.exit(1);
    }
    System.out.println(
        "ok: " + signed.length + " bytes (payload " + payload.length + " + trailer) decode to seq "
            + d.seq);
  }
}
