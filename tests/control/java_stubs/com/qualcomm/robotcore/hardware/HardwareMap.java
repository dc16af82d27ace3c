// motorlab test stub, written from the vendor's public API signatures (no vendor code): compile-time only.
package com.qualcomm.robotcore.hardware;
import java.util.ArrayList;
import java.util.Iterator;
public class HardwareMap {
    public DeviceMapping<VoltageSensor> voltageSensor = new DeviceMapping<VoltageSensor>();
    public <T> T get(Class<? extends T> classOrInterface, String deviceName) { return null; }
    public class DeviceMapping<D extends HardwareDevice> implements Iterable<D> {
        public Iterator<D> iterator() { return new ArrayList<D>().iterator(); }
    }
}
