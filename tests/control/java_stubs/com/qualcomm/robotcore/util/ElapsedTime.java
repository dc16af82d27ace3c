// motorlab test stub, written from the vendor's public API signatures (no vendor code): compile-time only.
package com.qualcomm.robotcore.util;
public class ElapsedTime {
    public double seconds() { return 0.0; }
    public void reset() {}
}
